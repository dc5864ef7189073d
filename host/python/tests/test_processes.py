"""Children started by mocap.processes end with their parent, however the parent ends."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

PARENT = """
import subprocess, sys, time
from mocap import processes
child = subprocess.Popen(["sleep", "60"], preexec_fn=processes.die_with_parent())
print(child.pid, flush=True)
time.sleep(60)
"""


def reaped_within(pid: int, seconds: float) -> bool:
    """pid (this process's child now: pytest is the suite's subreaper) ended and was reaped."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            done, _ = os.waitpid(pid, os.WNOHANG)
        except ChildProcessError:  # reaped already, or not ours
            return not os.path.exists(f"/proc/{pid}")
        if done:
            return True
        time.sleep(0.05)
    return False


@pytest.mark.parametrize("how", [signal.SIGKILL, signal.SIGTERM])
def test_a_spawned_child_ends_with_its_parent(how):
    parent = subprocess.Popen([sys.executable, "-c", PARENT], stdout=subprocess.PIPE, text=True)
    child = int(parent.stdout.readline())
    try:
        assert os.path.exists(f"/proc/{child}")
        parent.send_signal(how)
        parent.wait(timeout=10)
        assert reaped_within(child, 5.0), f"the child {child} outlived its parent"
    finally:
        parent.stdout.close()
        if os.path.exists(f"/proc/{child}"):
            os.kill(child, signal.SIGKILL)
            reaped_within(child, 5.0)
