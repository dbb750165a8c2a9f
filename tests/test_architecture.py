"""The layout rules of docs/architecture.md, checked on the source."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "knitlad"
MAX_FUNCTION_LINES = 80
MAX_CLASS_LINES = 250


def _definitions():
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                yield path.relative_to(PACKAGE.parent), node, node.end_lineno - node.lineno + 1


def test_no_function_outside_the_kernels_is_longer_than_80_lines_and_no_class_than_250():
    long = [f"{path}:{node.lineno} {node.name} ({n} lines)" for path, node, n in _definitions()
            if (isinstance(node, ast.ClassDef) and n > MAX_CLASS_LINES)
            or (not isinstance(node, ast.ClassDef) and n > MAX_FUNCTION_LINES and path.parts[1] != "kernels")]
    assert not long, long


def test_kernels_import_nothing_above_them():
    """Kernels depend on numpy, numba and each other only (docs/architecture.md, the dependency rule)."""
    for path in sorted((PACKAGE / "kernels").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("knitlad"):
                assert node.module.startswith("knitlad.kernels"), f"{path.name} imports {node.module}"


def test_no_module_calls_a_private_function_of_another():
    """A name with a leading underscore is used only in the module that defines it."""
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("knitlad"):
                private = [a.name for a in node.names if a.name.startswith("_") and not a.name.endswith("__")]
                assert not private, f"{path.name} imports {private} from {node.module}"


# the layers of docs/architecture.md, bottom up: a module imports only from its own layer or below
LAYERS = {
    1: ("kernels", "units", "measure", "stretching", "presets", "provenance", "progress", "deprecation"),
    2: ("state", "topology", "observers"),
    3: ("contact", "timestep", "natural_curvature", "scenes", "obstacles"),
    4: ("simulation", "quasistatic", "runloop"),
    5: ("protocol", "stitch_model", "loop_model", "periodic_loop", "cycling", "demo"),
    6: ("config",),
    7: ("io", "plots", "render", "registry"),
    8: ("sweep", "cluster", "runner", "ensemble"),
    9: ("cli", "__main__"),
}


def _layer(module: str) -> int:
    top = module.split(".")[1]
    return next(k for k, names in LAYERS.items() if top in names)


def test_every_module_imports_only_from_its_layer_or_below():
    """docs/architecture.md's layer rule, for every module of the package, lazy imports included (an
    import inside a function is still a dependency): no cycle between layers can form."""
    upward = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if len(parts) == 1:
            continue  # knitlad/__init__.py: the public names, re-exported
        module = ".".join(parts)
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("knitlad"):
                names = [f"knitlad.{a.name}" for a in node.names] if node.module == "knitlad" else [node.module]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names if a.name.startswith("knitlad.")]
            else:
                continue
            for name in names:
                if name != "knitlad.__version__" and _layer(name) > _layer(module):
                    upward.append(f"{module} (layer {_layer(module)}) imports {name} (layer {_layer(name)})")
    assert not upward, upward
