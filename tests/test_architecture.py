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
            or (not isinstance(node, ast.ClassDef) and n > MAX_FUNCTION_LINES and "kernels" not in path.parts)]
    assert not long, long


def test_kernels_import_nothing_above_them():
    """Kernels depend on numpy, numba and each other only (docs/architecture.md, the dependency rule)."""
    kernels = sorted((PACKAGE / "engine" / "kernels").glob("*.py"))
    assert len(kernels) > 5
    for path in kernels:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("knitlad"):
                assert node.module.startswith("knitlad.engine.kernels"), f"{path.name} imports {node.module}"


def test_no_module_calls_a_private_function_of_another():
    """A name with a leading underscore is used only in the module that defines it."""
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("knitlad"):
                private = [a.name for a in node.names if a.name.startswith("_") and not a.name.endswith("__")]
                assert not private, f"{path.name} imports {private} from {node.module}"


# the layers of docs/architecture.md, bottom up: each is a folder of the package (the command line and
# `python -m knitlad` on top); a module imports from its own folder or the folders below it
LAYERS = {1: "engine", 2: "fabric", 3: "experiments", 4: "io", 5: "viz", 6: "studies", 7: ("cli", "__main__")}


def _layer(module: str) -> int:
    top = module.split(".")[1]
    return next(k for k, names in LAYERS.items() if top == names or top in names)


def _module_imports() -> dict[str, set[str]]:
    """Every module of the package (``knitlad/__init__.py`` aside: it re-exports the public names) and the
    knitlad modules it imports, lazy imports included (an import inside a function is still a dependency)."""
    graph = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if len(parts) == 1:
            continue
        deps = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("knitlad"):
                base = node.module
                deps |= {f"{base}.{a.name}" if (PACKAGE.parent / base.replace(".", "/") / a.name).exists()
                         or (PACKAGE.parent / f"{base.replace('.', '/')}/{a.name}.py").exists() else base
                         for a in node.names}
            elif isinstance(node, ast.Import):
                deps |= {a.name for a in node.names if a.name.startswith("knitlad.")}
        graph[".".join(parts)] = deps - {"knitlad", ".".join(parts)}
    return graph


def test_every_folder_is_a_layer():
    """No module lies outside the layers (a new folder or top-level module must be given its place)."""
    graph = _module_imports()
    assert len(graph) > 60
    for module in graph:
        _layer(module)


def test_every_module_imports_only_from_its_layer_or_below():
    """docs/architecture.md's layer rule, for every module of every folder: no cycle between layers can form."""
    upward = [f"{m} (layer {_layer(m)}) imports {d} (layer {_layer(d)})"
              for m, deps in _module_imports().items() for d in sorted(deps) if _layer(d) > _layer(m)]
    assert not upward, upward


def test_no_import_cycle_between_modules():
    """Within a layer too, the modules import each other without a cycle (depth-first search)."""
    graph = _module_imports()
    state: dict[str, int] = {}
    cycles = []

    def visit(m: str, path: list[str]) -> None:
        state[m] = 1
        for d in sorted(graph.get(m, ())):
            if state.get(d) == 1:
                cycles.append(" -> ".join(path[path.index(d):] + [d]) if d in path else f"{m} -> {d}")
            elif d in graph and not state.get(d):
                visit(d, path + [d])
        state[m] = 2

    for m in sorted(graph):
        if not state.get(m):
            visit(m, [m])
    assert not cycles, cycles
