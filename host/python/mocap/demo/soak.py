"""The soak: the live simulated studio (mocap.demo.live_studio: 8 camera boxes, the IMU hub
and its nodes, mocapd, the recorder) for M minutes (`mocap bench --only soak --minutes M`):
frames that never came back, the host's latency p99 per 5-minute window, and every process's
resident memory and open file descriptors sampled from /proc. Beside each window: the inputs the
host dropped in it and what the machine did (each core's busy share and the time the hypervisor
stole, from /proc/stat), so a window that breaks the bound says whether the cause came from outside."""

from __future__ import annotations

import os
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from mocap.demo.live_studio import LiveStudio
from mocap.demo.play import Run
from mocap.demo.score import score
from mocap.demo.studio import prepare

SAMPLE_S = 5.0  # /proc sampling period
WINDOW_S = 300.0  # latency windows
WARM_UP_S = 120.0  # memory growth is fitted after it (allocators, caches, the solver's first frames)
# between launching the studio's dozen processes and the take's first frame: on two cores their
# start (interpreters, imports, each box reading its camera's part of the take) takes seconds,
# and a box still starting when the take begins loses its first frames (a studio's boxes are up
# long before a take)
LEAD_S = 10.0


def proc_sample(pid: int) -> tuple[float, int] | None:
    """(resident memory MB, open file descriptors) of pid from /proc; None once it ended."""
    try:
        with open(f"/proc/{pid}/status") as f:
            rss_kb = next(int(line.split()[1]) for line in f if line.startswith("VmRSS:"))
        return rss_kb / 1024.0, len(os.listdir(f"/proc/{pid}/fd"))
    except (OSError, StopIteration, ValueError):
        return None


def cpu_times() -> dict[str, tuple[int, int, int]]:
    """Per line of /proc/stat ("cpu" the machine, "cpu0"...): (busy, steal, total) in clock
    ticks since boot; busy excludes idle, iowait and steal."""
    out = {}
    with open("/proc/stat") as f:
        for line in f:
            if not line.startswith("cpu"):
                break
            name, *fields = line.split()
            user, nice, system, idle, iowait, irq, softirq, steal = (int(v) for v in fields[:8])
            out[name] = (user + nice + system + irq + softirq, steal,
                         user + nice + system + idle + iowait + irq + softirq + steal)
    return out


def _sample(live: LiveStudio, stop: threading.Event, samples: dict[str, list], cpu: list) -> None:
    """Every SAMPLE_S: (take s, RSS MB, fds) of each process, by name, and (take s,
    cpu_times()), until stop."""
    while not stop.wait(SAMPLE_S):
        t = live.take_s(time.time_ns())
        cpu.append((t, cpu_times()))
        for name, pid in live.pids().items():
            if (got := proc_sample(pid)) is not None:
                samples.setdefault(name, []).append((t, *got))


def _bounds(window_s: float, n: int) -> list[tuple[float, float]]:
    return [(i * window_s, (i + 1) * window_s) for i in range(n)]


def cpu_windows(cpu: list, n: int, window_s: float = WINDOW_S) -> list[dict]:
    """Per latency window: each core's busy share and the machine's stolen share (%) between
    the samples nearest its bounds."""
    out = []
    for lo, hi in _bounds(window_s, n):
        inside = [c for t, c in cpu if lo <= t <= hi]
        if len(inside) < 2:
            out.append({})
            continue
        a, b = inside[0], inside[-1]
        row = {}
        for name in b:
            busy, steal, total = (y - x for x, y in zip(a[name], b[name]))
            if total > 0:
                if name == "cpu":
                    row["steal_pct"] = round(100.0 * steal / total, 2)
                else:
                    row[f"{name}_busy_pct"] = round(100.0 * busy / total, 1)
        out.append(row)
    return out


def dropped_windows(healths: list, take_s_of, n: int, window_s: float = WINDOW_S) -> list[int]:
    """Per latency window: inputs the host dropped in it (late, stale clock, malformed: its
    Health's per-stream counts, which only grow, differenced across the window)."""
    totals = [(take_s_of(h.time_ns), sum(s.dropped for s in h.streams)) for h in healths if h.source == "host"]
    out = []
    for lo, hi in _bounds(window_s, n):
        before = [d for t, d in totals if t <= lo]
        upto = [d for t, d in totals if t <= hi]
        out.append((upto[-1] if upto else 0) - (before[-1] if before else 0))
    return out


def memory(samples: dict[str, list], warm_up_s: float = WARM_UP_S) -> dict:
    """Per process: RSS after the warm-up and at the end (MB), its growth fitted after the
    warm-up (MB per 10 minutes, least squares), and the file descriptors at start and end, their
    most and after the warm-up."""
    out = {}
    for name, rows in sorted(samples.items()):
        a = np.array(rows)
        late = a[a[:, 0] >= warm_up_s]
        slope = float(np.polyfit(late[:, 0], late[:, 1], 1)[0]) * 600.0 if len(late) >= 3 else None
        out[name] = {"rss_mb_after_warm_up": round(float(late[0, 1]), 1) if len(late) else None,
                     "rss_mb_end": round(float(a[-1, 1]), 1),
                     "rss_growth_mb_per_10min": round(slope, 3) if slope is not None else None,
                     "fds": [int(a[0, 2]), int(a[-1, 2])], "fds_max": int(a[:, 2].max()),
                     "fds_after_warm_up": int(late[0, 2]) if len(late) else None}
    return out


def latency_windows(take_s: np.ndarray, latency_ms: np.ndarray, window_s: float = WINDOW_S) -> list[float]:
    """The latency p99 (ms) of each whole window of window_s (a last partial one is kept when
    it holds at least half a window)."""
    out = []
    for lo in np.arange(0.0, take_s.max() + 1e-9, window_s):
        inside = (take_s >= lo) & (take_s < lo + window_s)
        if inside.any() and take_s[inside].max() - lo >= window_s / 2:
            out.append(round(float(np.percentile(latency_ms[inside], 99)), 2))
    return out


def bench(minutes: float = 10.0, realtime: bool = True, pin_host: bool = False) -> dict:
    """The `soak` benchmark line. realtime: mocapd under SCHED_FIFO, as the live benchmark and a
    deployed host run it; pin_host: mocapd alone on a core (LiveStudio)."""
    seconds = minutes * 60.0
    with tempfile.TemporaryDirectory() as tmp:
        # the truth's calibration: estimating one runs the whole take's camera messages through
        # the boxes' pieces first (mocap.demo.studio.calibrate), minutes for a long take
        studio = prepare(Path(tmp) / "studio", seconds, calibration="oracle")
        stop, samples, cpu = threading.Event(), {}, []
        with LiveStudio(studio, lead_s=LEAD_S, record=Path(tmp) / "take.mcap", realtime=realtime,
                        pin_host=pin_host) as live:
            sampler = threading.Thread(target=_sample, args=(live, stop, samples, cpu), daemon=True)
            sampler.start()
            live.wait(lambda arrived: live.take_s(time.time_ns()) > seconds + 1.0, live.lead_s + seconds + 60.0,
                      "the take's end")
            stop.set()
            sampler.join()
            host_realtime = live.scheduled_realtime("mocapd")
            host_cores, hub_cores = live.cores_of("mocapd"), live.cores_of("hub")  # pinned or not
            poses, healths = [a.message for a in live.poses()], [a.message for a in live.healths()]
        result = score(studio, Run(poses, healths, {}, live.start_ns))
        file_mb = (Path(tmp) / "take.mcap").stat().st_size / 1e6
    take_s = np.array([live.take_s(p.capture_time_ns) for p in poses])
    windows = latency_windows(take_s, np.array([p.latency_ms for p in poses]))
    last = healths[-1] if healths else None
    return {"bench": "soak", "minutes": minutes, "lead_s": LEAD_S, "host_realtime": host_realtime,
            "host_cores": host_cores, "hub_cores": hub_cores, "frames": result["frames"], "dropped": result["dropped"],
            "latency_p50_ms": result["latency_p50_ms"], "latency_p99_ms": result["latency_p99_ms"],
            "latency_p99_ms_by_5min": windows,
            "host_inputs_dropped_by_5min": dropped_windows(healths, live.take_s, len(windows)),
            "cpu_by_5min": cpu_windows(cpu, len(windows)),
            "latency_p99_spread_pct": round(100.0 * (max(windows) / min(windows) - 1.0), 1) if windows else None,
            "joint_centres_pos_cm": result.get("joint_centres_pos_cm"), "recording_mb": round(file_mb, 1),
            "host_inputs_dropped": {s.stream: s.dropped for s in (last.streams if last else []) if s.dropped},
            "processes": memory(samples)}
