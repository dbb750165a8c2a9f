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
