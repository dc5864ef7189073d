"""What the atheris targets of tests/fuzz share: a decoder is fed any input and may fail only
with the project's own clear error types; any other exception is a finding (atheris reports it
as a crash and writes the input). Run a target with libFuzzer's flags, e.g.
`python tests/fuzz/fuzz_bvh.py -max_total_time=60 CORPUS_DIR SEED_DIR` (scripts/fuzz.py runs
them all)."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import atheris


def scratch(prefix: str) -> Path:
    """A temporary folder in $TMPDIR (libFuzzer ends the process without Python's exit handlers:
    scripts/fuzz.py gives each run its own TMPDIR and removes it after)."""
    return Path(tempfile.mkdtemp(prefix=prefix))


def main(check, allowed: tuple[type[BaseException], ...]) -> None:
    """Fuzzes check(data: bytes); an exception of `allowed` is the decoder refusing the input."""

    def test_one_input(data: bytes) -> None:
        try:
            check(data)
        except allowed:
            pass

    atheris.Setup(sys.argv, test_one_input)
    atheris.Fuzz()


class Folder:
    """A private copy of a folder of valid files; `replaced(name, data)` puts `data` in one of them
    for the length of a `with` block."""

    def __init__(self, make) -> None:
        self.path = scratch("mocap_fuzz_")
        make(self.path)
        self._valid = {p.relative_to(self.path): p.read_bytes() for p in self.path.rglob("*") if p.is_file()}

    @property
    def files(self) -> list[Path]:
        return sorted(self._valid)

    def replaced(self, name: Path, data: bytes):
        folder = self

        class _Swap:
            def __enter__(self):
                (folder.path / name).write_bytes(data)
                return folder.path

            def __exit__(self, *exc):
                (folder.path / name).write_bytes(folder._valid[name])

        return _Swap()
