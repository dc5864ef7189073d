#!/usr/bin/env python3
"""Size limits of the Python code (`make lint`): no function over MAX_FUNCTION_LINES lines and
no module over MAX_MODULE_LINES lines, except where ALLOWED says why.

    python scripts/check_sizes.py DIR...   # prints each breach as path:line: message; exit 1 if any

A function's size runs from its `def` line to its last line (docstring and nested
functions included, decorators not); a module's is its line count. Generated modules
(*_pb2.py, from proto/ at build time) are not checked.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

MAX_FUNCTION_LINES = 60
MAX_MODULE_LINES = 400

# Exceptions, each with its reason: "path" (a module) or "path::function" -> the limit it may
# reach instead. None today: every function and module fits. An entry names the one place and
# says why splitting would make it harder to read, e.g.
#   "host/python/mocap/example.py::table": (80, "one Markdown table, row by row, read top to bottom"),
ALLOWED: dict[str, tuple[int, str]] = {}


def _functions(tree: ast.AST):
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield node


def breaches(path: Path, shown: str) -> list[str]:
    """The size breaches of one module; shown: its path as ALLOWED and the messages name it."""
    text = path.read_text()
    out = []
    lines = len(text.splitlines())
    if lines > ALLOWED.get(shown, (MAX_MODULE_LINES, ""))[0]:
        out.append(f"{shown}:1: module of {lines} lines (limit {MAX_MODULE_LINES})")
    for node in _functions(ast.parse(text, str(path))):
        length = node.end_lineno - node.lineno + 1
        if length > ALLOWED.get(f"{shown}::{node.name}", (MAX_FUNCTION_LINES, ""))[0]:
            out.append(f"{shown}:{node.lineno}: function {node.name} of {length} lines (limit {MAX_FUNCTION_LINES})")
    return out


def main(roots: list[str]) -> int:
    found, seen = [], set()
    for root in roots:
        for path in sorted(Path(root).rglob("*.py")):
            if path.name.endswith("_pb2.py"):
                continue
            shown = path.as_posix()
            seen.add(shown)
            found += breaches(path, shown)
    stale = [key for key in ALLOWED if key.split("::")[0] not in seen]
    found += [f"{key}: in ALLOWED but no such module was checked" for key in stale]
    for line in found:
        print(line)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:] or ["host/python", "edge/python"]))
