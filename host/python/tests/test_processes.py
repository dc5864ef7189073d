"""Children started by mocap.processes end with their parent, however the parent ends; a process
pinned to cores has every thread there, and the threads it starts later."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from mocap import processes

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


def test_pin_moves_every_thread_of_a_process_and_its_later_threads():
    host, edge = processes.host_and_edge_cores()
    assert host not in edge and edge | {host} == os.sched_getaffinity(0)
    code = ("import threading, time, os\n"
            "threading.Thread(target=time.sleep, args=(30,), daemon=True).start()\n"
            "print('started', flush=True); input()\n"
            "t = threading.Thread(target=time.sleep, args=(30,), daemon=True); t.start()\n"
            "print(sorted(os.sched_getaffinity(t.native_id)), flush=True); time.sleep(30)\n")
    child = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "started"
        processes.pin(child.pid, {host})
        tasks = os.listdir(f"/proc/{child.pid}/task")
        assert len(tasks) >= 2 and all(os.sched_getaffinity(int(t)) == {host} for t in tasks)
        child.stdin.write("\n")
        child.stdin.flush()
        assert child.stdout.readline().strip() == str([host])  # a thread started after the pin
    finally:
        child.kill()
        child.wait()
    processes.pin(child.pid, {host})  # an ended process is left alone
