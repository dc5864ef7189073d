"""Child processes that end with their parent. A child is started with the kernel's parent-death
signal (prctl PR_SET_PDEATHSIG, SIGKILL), so that a parent ended by any signal, SIGKILL
included, when none of its own clean-up runs, leaves none of its children behind. The signal is
sent when the *thread* that started the child ends: start children from a thread that outlives
them (the main thread). Linux only, as mocapd."""

from __future__ import annotations

import ctypes
import os
import signal
from collections.abc import Callable

PR_SET_PDEATHSIG = 1  # prctl(2)


def die_with_parent(core: int | None = None) -> Callable[[], None]:
    """A preexec_fn for subprocess.Popen: the child is killed when this process ends; with
    core, it is pinned to that CPU."""
    parent = os.getpid()
    prctl = ctypes.CDLL(None, use_errno=True).prctl  # looked up before the fork, not in the child

    def setup() -> None:
        if core is not None:
            os.sched_setaffinity(0, {core})
        prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL))
        if os.getppid() != parent:  # the parent died before prctl
            os._exit(1)
    return setup


def pin(pid: int, cores: set[int]) -> None:
    """Every thread of process pid onto `cores` (threads it starts later inherit it); a process
    that has ended is left alone."""
    try:
        tasks = os.listdir(f"/proc/{pid}/task")
    except FileNotFoundError:
        return
    for tid in tasks:
        try:
            os.sched_setaffinity(int(tid), cores)
        except ProcessLookupError:  # the thread ended meanwhile
            pass


def host_and_edge_cores() -> tuple[int, set[int]]:
    """A machine's cores split as a deployed host would (systemd's CPUAffinity=): the last one
    for mocapd alone, the others for everything else."""
    cores = sorted(os.sched_getaffinity(0))
    if len(cores) < 2:
        raise ValueError("pinning mocapd to a core of its own needs at least 2 cores")
    return cores[-1], set(cores[:-1])
