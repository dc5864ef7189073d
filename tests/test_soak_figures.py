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


def test_each_window_has_the_host_drops_in_it_and_the_cores_share():
    from types import SimpleNamespace as NS
    stream = lambda dropped: NS(stream="cam0", dropped=dropped)  # noqa: E731
    healths = [NS(source="host", time_ns=int(t * 1e9), streams=[stream(d), stream(1)])
               for t, d in [(10, 0), (290, 5), (310, 5), (590, 45), (610, 45)]]
    healths.insert(2, NS(source="hub0", time_ns=int(300e9), streams=[stream(1000)]))  # not the host's
    assert soak.dropped_windows(healths, lambda ns: ns / 1e9, 2) == [6, 40]

    def times(busy0, busy1, steal):  # 100 ticks per core per sample step
        return {"cpu": (busy0 + busy1, steal, 200), "cpu0": (busy0, 0, 100), "cpu1": (busy1, steal, 100)}
    cpu, total = [], {k: (0, 0, 0) for k in ("cpu", "cpu0", "cpu1")}
    for t in range(0, 601, 5):
        step = times(50, 20, 0) if t <= 300 else times(90, 60, 10)
        total = {k: tuple(a + b for a, b in zip(total[k], step[k])) for k in step}
        cpu.append((float(t), total))
    first, second = soak.cpu_windows(cpu, 2)
    assert first == {"steal_pct": 0.0, "cpu0_busy_pct": 50.0, "cpu1_busy_pct": 20.0}
    assert second["steal_pct"] == 5.0 and second["cpu0_busy_pct"] == 90.0 and second["cpu1_busy_pct"] == 60.0


def test_the_machine_s_cpu_times_are_read_and_only_grow():
    a = soak.cpu_times()
    b = soak.cpu_times()
    assert "cpu" in a and "cpu0" in a and set(a) == set(b)
    for name in a:
        busy, steal, total = a[name]
        assert 0 <= busy <= total and 0 <= steal <= total
        assert all(y >= x for x, y in zip(a[name], b[name]))
