#!/usr/bin/env python3
"""Size limits of the Python, C and C++ code (`make lint`): no function over
MAX_FUNCTION_LINES lines and no module (source or header file) over MAX_MODULE_LINES lines,
except where ALLOWED says why.

    python scripts/check_sizes.py DIR...   # prints each breach as path:line: message; exit 1 if any

A Python function's size runs from its `def` line to its last line (docstring and nested
functions included, decorators not). A C or C++ function's runs from the first line of its
signature to its closing brace: a brace block at file scope (namespaces do not count) whose
header has a parameter list — a gtest TEST body counts as a function. A module's size is its
line count. Generated modules (*_pb2.py, from proto/ at build time) are not checked.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

MAX_FUNCTION_LINES = 60
MAX_MODULE_LINES = 400

# Exceptions, each with its reason: "path" (a module) or "path::function" -> the limit it may
# reach instead. None today: every function and module fits. An entry names the one place and
# says why splitting would make it harder to read, e.g.
#   "host/python/mocap/example.py::table": (80, "one Markdown table, row by row, read top to bottom"),
ALLOWED: dict[str, tuple[int, str]] = {
    "firmware/tests/test_icm42688.c": (
        580, "one cmocka program over one fake-chip fixture (its setup, its source of motion, its "
             "read-and-compare): split, the fixture would move to tests/support/ for a second program"),
    "firmware/tests/test_sample_clock.c": (
        450, "one cmocka program over one simulated clock pair; its 15 tests share the drift and "
             "jitter generators"),
}
C_SUFFIXES = (".c", ".cc", ".h")


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


def _c_code(text: str) -> str:
    """The text without comments, string and character literals or preprocessor lines (line
    breaks kept, so that line numbers stay)."""
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r'"(\\.|[^"\\\n])*"', '""', text)
    text = re.sub(r"'(\\.|[^'\\\n])*'", "''", text)
    return re.sub(r"^[ \t]*#[^\n]*(\\\n[^\n]*)*", "", text, flags=re.M)


def c_functions(text: str) -> list[tuple[str, int, int]]:
    """(header, first line, lines) of each function body at file scope of C/C++ source."""
    out, stack, header, line = [], [], "", 1  # stack: (kind, header's first line, header)
    for ch in _c_code(text):
        if ch == "{":
            h = header.strip()
            at_file_scope = all(kind == "namespace" for kind, _, _ in stack)
            if re.match(r"(namespace|extern)\b", h):
                kind = "namespace"
            elif at_file_scope and ")" in h and not re.match(r"(typedef|struct|class|enum|union)\b", h):
                kind = "function"
            else:
                kind = "block"
            stack.append((kind, line - h.count("\n"), " ".join(h.split())[:60]))
            header = ""
        elif ch == "}":
            if stack:
                kind, first, h = stack.pop()
                if kind == "function":
                    out.append((h, first, line - first + 1))
            header = ""
        elif ch == ";":
            header = ""
        else:
            header += ch
        line += ch == "\n"
    return out


def c_breaches(path: Path, shown: str) -> list[str]:
    text = path.read_text()
    lines = len(text.splitlines())
    out = []
    if lines > ALLOWED.get(shown, (MAX_MODULE_LINES, ""))[0]:
        out.append(f"{shown}:1: module of {lines} lines (limit {MAX_MODULE_LINES})")
    for header, first, length in c_functions(text):
        if length > MAX_FUNCTION_LINES:
            out.append(f"{shown}:{first}: function of {length} lines (limit {MAX_FUNCTION_LINES}): {header}")
    return out


def main(roots: list[str]) -> int:
    found, seen = [], set()
    for root in roots:
        for path in sorted(p for p in Path(root).rglob("*") if p.is_file()):
            shown = path.as_posix()
            if path.suffix == ".py" and not path.name.endswith("_pb2.py"):
                found += breaches(path, shown)
            elif path.suffix in C_SUFFIXES:
                found += c_breaches(path, shown)
            else:
                continue
            seen.add(shown)
    checked = [Path(root).as_posix().rstrip("/") + "/" for root in roots]
    stale = [key for key in ALLOWED if key.split("::")[0] not in seen and key.startswith(tuple(checked))]
    found += [f"{key}: in ALLOWED but no such module was checked" for key in stale]
    for line in found:
        print(line)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:] or ["host", "edge", "firmware", "tests"]))
