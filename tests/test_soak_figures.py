"""The soak's figures (mocap.demo.soak): memory growth fitted after the warm-up, latency p99
per window, and /proc sampling of a live process."""

import os
import subprocess
import sys
import time

import numpy as np

from mocap.demo import soak


def test_memory_growth_is_fitted_after_the_warm_up_and_descriptors_kept():
    t = np.arange(0.0, 600.0, 5.0)
    rss = np.where(t < 120, 50 + t / 4, 80 + t * 0.5 / 600)  # fast warm-up, then 0.5 MB per 10 min
    fds = np.where(t < 300, 12, 13)
    out = soak.memory({"mocapd": list(zip(t, rss, fds))})["mocapd"]
    assert abs(out["rss_growth_mb_per_10min"] - 0.5) < 1e-6
    assert out["rss_mb_after_warm_up"] == 80.1 and out["fds"] == [12, 13] and out["fds_max"] == 13
    assert out["fds_after_warm_up"] == 12


def test_latency_p99_per_window_keeps_whole_windows_and_a_last_half():
    t = np.arange(0.0, 750.0, 1 / 60)
    latency = np.where(t < 300, 2.0, 4.0)
    assert soak.latency_windows(t, latency) == [2.0, 4.0]  # the last 150 s: under half a window
    assert soak.latency_windows(t, latency, window_s=490.0) == [4.0, 4.0]  # the last: over half a window


def test_a_process_is_sampled_from_proc_until_it_ends():
    child = subprocess.Popen([sys.executable, "-c", "import sys; b = bytearray(64 << 20); sys.stdin.read()"],
                             stdin=subprocess.PIPE)
    try:
        got, deadline = None, time.monotonic() + 30
        while (got is None or got[0] < 64) and time.monotonic() < deadline:  # until it holds its 64 MB
            got = soak.proc_sample(child.pid)
        assert got[0] >= 64
        assert got[1] >= 3  # stdin, stdout, stderr
    finally:
        child.stdin.close()
        child.wait(timeout=10)
    assert soak.proc_sample(child.pid) is None and soak.proc_sample(os.getpid()) is not None
