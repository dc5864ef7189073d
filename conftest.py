"""The whole suite's last check: no process it started outlives it.

pytest is made a child subreaper (prctl PR_SET_CHILD_SUBREAPER), so a process whose parent
ended under a test (a worker of a killed calibrator, a daemon that detached) is re-parented
to pytest instead of init and stays among its descendants. When the session finishes, every
descendant still running (zombies have ended) is given GRACE_S to end — a test may have just
stopped it — then each one left is named, killed, and the session fails. The interpreter's
own helpers, which end with the pytest process by design, are not the suite's leftovers.
"""

from __future__ import annotations

import collections
import ctypes
import os
import select
import signal
import time

import pytest

PR_SET_CHILD_SUBREAPER = 36  # prctl(2)
GRACE_S = 10.0
# multiprocessing's resource tracker and fork server read a pipe only this process holds, and
# end when it does; pytest-xdist's workers (execnet) are pytest itself.
HELPERS = ("from multiprocessing.resource_tracker import main", "from multiprocessing.forkserver import main",
           "execnet")


def pytest_configure(config) -> None:
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) != 0:
        config.issue_config_time_warning(pytest.PytestWarning(
            f"PR_SET_CHILD_SUBREAPER failed ({os.strerror(ctypes.get_errno())}): orphans escape the process check"),
            stacklevel=2)


def running_descendants(root: int) -> dict[int, str]:
    """pid -> command line of every descendant of `root` that has not ended (from /proc)."""
    children = collections.defaultdict(list)
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    state, parent = f.read().rsplit(")", 1)[1].split()[:2]
            except (OSError, ValueError):
                continue  # ended while listed
            children[int(parent)].append((int(entry), state))
    found, stack = {}, [root]
    while stack:
        for pid, state in children.get(stack.pop(), []):
            stack.append(pid)
            if state not in ("Z", "X"):
                found[pid] = _command(pid)
    return found


def _command(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return f.read().replace(b"\0", b" ").decode("utf-8", "replace").strip() or f"[pid {pid}]"
    except OSError:
        return f"[pid {pid}]"


def _still_running(pids: list[int], timeout_s: float) -> list[int]:
    """The pids that have not ended within timeout_s (waiting on their pidfds)."""
    fds = {}
    for pid in pids:
        try:
            fds[os.pidfd_open(pid)] = pid
        except ProcessLookupError:
            pass
    deadline = time.monotonic() + timeout_s
    try:
        while fds and (left := deadline - time.monotonic()) > 0:
            for fd in select.select(list(fds), [], [], left)[0]:
                os.close(fd)
                del fds[fd]
        return sorted(fds.values())
    finally:
        for fd in fds:
            os.close(fd)


@pytest.hookimpl(trylast=True)
def pytest_sessionfinish(session, exitstatus) -> None:
    found = {pid: cmd for pid, cmd in running_descendants(os.getpid()).items()
             if not any(helper in cmd for helper in HELPERS)}
    # Read again after the grace: a process listed in the middle of its exec has no command line yet.
    left = {pid: _command(pid) for pid in _still_running(list(found), GRACE_S)}
    left = {pid: cmd for pid, cmd in left.items() if not any(helper in cmd for helper in HELPERS)}
    if not left:
        return
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    lines = [f"{len(left)} process(es) started by the suite still running {GRACE_S:.0f} s after it ended "
             "(killed now):", *(f"  pid {pid}: {cmd}" for pid, cmd in left.items())]
    if reporter is not None:
        reporter.write_sep("=", "processes left running", red=True, bold=True)
    for line in lines:
        if reporter is not None:
            reporter.write_line(line, red=True, bold=True)
        else:
            print(line)
    for pid in left:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    session.exitstatus = pytest.ExitCode.TESTS_FAILED
