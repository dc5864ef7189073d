"""The third-party Python modules the edge boxes import, read from the code (every module
scripts/edge_dist.py puts in the edge's distribution), and the distribution package each comes
from on this machine. An import is optional when the code carries on without it: inside a try
whose ImportError handler does not raise (picamera2: the project's libcamera adapter
otherwise); an import a handler turns into the feature's error is required."""

from __future__ import annotations

import ast
import importlib.metadata
import sys
from pathlib import Path

from install_tree import edge_dist

DYNAMIC = ("import_module", "require_module")  # importlib.import_module("x"), sources.base.require_module("x", ...)
PROJECT = ("mocap", "mocap_edge")


def _imported_name(node: ast.AST) -> str | None:
    if isinstance(node, ast.Import):
        return node.names[0].name
    if isinstance(node, ast.ImportFrom) and not node.level:
        return node.module
    if isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
        func = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
        if func in DYNAMIC and isinstance(node.args[0].value, str):
            return node.args[0].value
    return None


def _falls_back(handlers: list[ast.ExceptHandler]) -> bool:
    """An ImportError handler that carries on (raises nothing)."""
    for h in handlers:
        names = {getattr(n, "id", None) for n in (h.type.elts if isinstance(h.type, ast.Tuple) else [h.type])}
        if names & {"ImportError", "ModuleNotFoundError"}:
            return not any(isinstance(n, ast.Raise) for n in ast.walk(h))
    return False


def imports(path: Path) -> dict[str, bool]:
    """Top-level module -> required, for one source file."""
    found: dict[str, bool] = {}
    optional_nodes = set()
    tree = ast.parse(path.read_text(), str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Try) and _falls_back(node.handlers):
            optional_nodes |= {id(n) for stmt in node.body for n in ast.walk(stmt)}
    for node in ast.walk(tree):
        name = _imported_name(node)
        top = name.split(".")[0] if name else None
        if top and top not in sys.stdlib_module_names and top not in PROJECT and top != "__future__":
            found[top] = found.get(top, False) or id(node) not in optional_nodes
    return found


def edge_imports() -> dict[str, bool]:
    """Top-level third-party module -> required, over the edge's whole distribution."""
    found: dict[str, bool] = {}
    for module in edge_dist.closure():
        path = edge_dist.module_file(module)
        if path is None:  # generated (the wire's modules): protobuf, as their package's __init__ says
            continue
        for top, required in imports(path).items():
            found[top] = found.get(top, False) or required
    found["google"] = True  # the generated wire modules import google.protobuf
    return found


def distribution(module: str) -> str | None:
    """The installed distribution providing a top-level module (None: not installed here)."""
    names = importlib.metadata.packages_distributions().get(module)
    return names[0] if names else None


def package_name(dist: str, renamed: dict[str, str]) -> str:
    """OpenEmbedded's package of a Python distribution: python3-<name>, lower case, a leading
    python- dropped, unless `renamed` says otherwise."""
    if dist in renamed:
        return renamed[dist]
    name = dist.lower().replace("_", "-")
    return "python3-" + name.removeprefix("python-")
