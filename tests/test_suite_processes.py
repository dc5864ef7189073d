"""The suite's last check (the repository's conftest.py): a run fails when a process it
started is still running at its end — orphans included — and leaves none behind; the
interpreter's helpers that end with pytest are not flagged. Each case is a pytest run of its
own in a folder with a copy of that conftest.py."""

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TIMEOUT_S = 120.0  # bound on a nested pytest run (its own grace is 10 s)


def run_suite(folder: Path, tests: str) -> subprocess.CompletedProcess:
    shutil.copy(ROOT / "conftest.py", folder / "conftest.py")
    (folder / "test_case.py").write_text(textwrap.dedent(tests))
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(folder)], cwd=folder,
                          capture_output=True, text=True, timeout=TIMEOUT_S)


def test_a_process_left_running_fails_the_run_and_is_ended(tmp_path):
    marker = f"{tmp_path}/leftover"  # in the leftovers' command lines
    sleeper = f"{sys.executable} -c 'import time; time.sleep(600)'"
    result = run_suite(tmp_path, f"""
        import subprocess
        def test_forgets_a_child():
            subprocess.Popen("exec " + {sleeper!r} + " {marker}-child", shell=True)
        def test_leaves_an_orphan():  # its parent (sh) ends at once: it is re-parented
            subprocess.run({sleeper!r} + " {marker}-orphan & exit 0", shell=True, check=True)
    """)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "2 passed" in result.stdout and "2 process(es) started by the suite still running" in result.stdout
    assert f"{marker}-child" in result.stdout and f"{marker}-orphan" in result.stdout
    assert not _running(marker), "the check left them running"


def test_a_run_that_ends_what_it_started_passes(tmp_path):
    result = run_suite(tmp_path, """
        import multiprocessing, subprocess
        def test_ends_its_child():
            child = subprocess.Popen(["sleep", "600"])
            child.terminate()
            child.wait()
        def test_starts_the_interpreters_helper():  # multiprocessing's resource tracker: ends with pytest
            multiprocessing.get_context("spawn").Lock()
    """)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "still running" not in result.stdout


def _running(text: str) -> list[int]:
    found = []
    for entry in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{entry}/cmdline", "rb") as f:
                command = f.read().decode("utf-8", "replace")
            with open(f"/proc/{entry}/stat") as f:
                ended = f.read().rsplit(")", 1)[1].split()[0] == "Z"
        except OSError:
            continue
        if text in command and not ended:
            found.append(int(entry))
    return found
