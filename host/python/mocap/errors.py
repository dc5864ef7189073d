"""Exceptions of the mocap Python tools.

    MocapError             base of everything raised on purpose
    +-- InputError         a file or message is malformed or inconsistent
    |   +-- TakeError      a take folder's file is malformed (names the file, line, column)
    +-- DataMissingError   an optional data set (e.g. ../shared) is not present
"""

from __future__ import annotations

from pathlib import Path


class MocapError(Exception):
    pass


class InputError(MocapError):
    pass


class TakeError(InputError):
    """`path:line:column: message`; line and column (1-based) where the fault has one."""

    def __init__(self, path: str | Path, message: str, line: int | None = None, column: int | None = None):
        where = str(path) + (f":{line}" if line else "") + (f":{column}" if line and column else "")
        super().__init__(f"{where}: {message}")
        self.path, self.line, self.column = Path(path), line, column


class DataMissingError(MocapError):
    pass
