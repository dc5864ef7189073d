"""Crash drills of the live system on the simulated studio (mocap.demo.live_studio), each
during a live take with a recording running (`mocap bench --only drill`,
tests/test_crash_drills.py):

- edge: SIGKILL to a camera box, then to the IMU hub, each started again: the solve goes on
  with what remains, the streams rejoin, Health reports the gap, and the recording holds
  every message the boxes published but for the killed box's own gap (counted by sequence);
- host: SIGKILL to mocapd, started again as systemd would: it publishes again with the
  session's calibration;
- clock: a camera box's clock steps +1 s and back, then -1 s and back (a PTP loss): the host
  counts the steps, refuses the box's frames meanwhile, and the other streams go on.

Each returns its figures (seconds, counts); the bounds are asserted by the tests."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from mocap.demo import recording_check
from mocap.demo.live_studio import Arrived, LiveStudio
from mocap.demo.play import Run
from mocap.demo.score import score
from mocap.demo.studio import Studio, prepare
from mocap.net import wire

SECONDS = 16.0  # of the drills' take
CAMERA, SENSOR, STEPPED = "cam3", "lower_back", "cam2"
WAIT_S = 20.0  # bound on every wait for what the host publishes (the machine may be loaded)
PERIOD_S = 1 / 60
CLOCK_STEPS = ((3.0, 1.0), (4.0, 0.0), (5.0, -1.0), (6.0, 0.0))  # (take s, the box's clock off by s)
# Between launching the processes and the take's start: on this 2-core machine shared with
# builds (load 16-19) a dozen Python processes took 5 s and more to start, and a box that opens
# its camera after the take started captures from then on.
LEAD_S = 10.0


def studio(folder: Path, seed: int = 5) -> Studio:
    """The drills' studio: 8 cameras, 13 IMUs, SECONDS of take, the truth's calibration."""
    return prepare(folder, SECONDS, seed=seed, calibration="oracle")


def _pose(live: LiveStudio, after_ns: int, test=lambda p: True):
    """A finder of the first PoseFrame that arrived after after_ns and passes test."""
    return lambda arrived: next((a for a in arrived if a.time_ns > after_ns and isinstance(a.message, wire.PoseFrame)
                                 and test(a.message)), None)


def _health(after_ns: int, stream: str, test):
    """A finder of the first Health that arrived after after_ns whose `stream` passes test."""
    def find(arrived: list[Arrived]):
        for a in arrived:
            if a.time_ns > after_ns and isinstance(a.message, wire.Health):
                s = next((s for s in a.message.streams if s.stream == stream), None)
                if s is not None and test(s):
                    return a
        return None
    return find


def _until_take(live: LiveStudio, take_s: float) -> None:
    live.wait(_pose(live, 0, lambda p: live.take_s(p.capture_time_ns) >= take_s), live.lead_s + take_s + WAIT_S,
              f"a pose of take time {take_s} s")


def _kill_and_restart(live: LiveStudio, name: str, stream: str, rejoined) -> dict:
    """SIGKILL to `name`; waits for the solve to go on past it and for Health to report
    `stream` inactive; starts it again and waits for a pose that `rejoined`."""
    killed = live.kill(name)
    live.wait(_pose(live, killed, lambda p: p.capture_time_ns > killed + 300_000_000), WAIT_S, f"poses after {name}")
    reported = live.wait(_health(killed, stream, lambda s: not s.active), WAIT_S, f"Health: {stream} inactive")
    restarted = live.restart(name)
    back = live.wait(_pose(live, restarted, rejoined), WAIT_S, f"{stream} back in a pose")
    return {"killed_ns": killed, "restarted_ns": restarted, "rejoin_s": (back.time_ns - restarted) * 1e-9,
            "reported_inactive_after_s": (reported.time_ns - killed) * 1e-9}


def _continuity(live: LiveStudio, around_ns: int) -> dict:
    """The poses around a kill (from 0.5 s before to 1.5 s after): frame periods the solve
    skipped, how much later than before the kill the poses were published at most (s), and
    by how much in the median over the 300 ms after it (the frames a box's silence alone
    would hold for max_wait until it is stale)."""
    poses = sorted((a.message.capture_time_ns, a.time_ns) for a in live.poses()
                   if -0.5e9 <= a.message.capture_time_ns - around_ns <= 1.5e9)
    t = np.array(poses, np.int64)
    before = t[t[:, 0] < around_ns]
    delay = (t[:, 1] - t[:, 0]) * 1e-9
    after = t[(t[:, 0] >= around_ns) & (t[:, 0] < around_ns + 300_000_000)]  # till a silent box is stale
    skipped = int(np.maximum(np.round(np.diff(t[:, 0]) * 1e-9 / PERIOD_S) - 1, 0).sum())
    usual = np.median((before[:, 1] - before[:, 0]) * 1e-9)
    return {"frames_skipped": skipped, "extra_delay_s": float(delay.max() - usual),
            "waited_after_kill_s": float(np.median((after[:, 1] - after[:, 0]) * 1e-9) - usual)}


def _unused(live: LiveStudio, camera: str, around_ns: int) -> int:
    """The frames around a kill (the longest run within 3 s after it) whose poses the camera
    is not in: what the solve went without, whether the box never sent them or mocapd never
    received them."""
    times = sorted(a.message.capture_time_ns for a in live.poses()
                   if camera in a.message.cameras and -0.5e9 <= a.message.capture_time_ns - around_ns <= 3e9)
    gaps = np.diff(np.array(times, np.int64)) * 1e-9 / PERIOD_S if len(times) > 1 else np.zeros(1)
    return int(max(np.round(gaps.max()) - 1, 0))


def edge(s: Studio, folder: Path) -> dict:
    """The edge drill: CAMERA's box killed 2 s into the take and started again, then the hub."""
    folder.mkdir(parents=True, exist_ok=True)
    with LiveStudio(s, lead_s=LEAD_S, record=folder / "take.mcap") as live:
        _until_take(live, 2.0)
        camera = _kill_and_restart(live, CAMERA, f"camera/{CAMERA}", lambda p: CAMERA in p.cameras)
        hub = _kill_and_restart(live, "hub", f"imu/{SENSOR}", lambda p: len(p.imus) + len(p.imus_distrusted) == 13)
        _until_take(live, live.take_s(hub["restarted_ns"]) + 1.5)
    kept = recording_check.check(folder / "take.mcap", s, live.start_ns, {CAMERA: camera, "hub0": hub})
    last = {x.stream: x for x in live.healths()[-1].message.streams}  # the gaps as Health counts them
    return {"drill": "edge", "camera": {**camera, **_continuity(live, camera["killed_ns"]),
                                        "health_lost": last[f"camera/{CAMERA}"].lost,
                                        "frames_without_it": _unused(live, CAMERA, camera["killed_ns"])},
            "hub": {**hub, **_continuity(live, hub["killed_ns"]), "health_lost": last[f"imu/{SENSOR}"].lost},
            "recording": kept}


def host(s: Studio, folder: Path) -> dict:
    """The host drill: mocapd killed 2.5 s into the take and started again at once."""
    folder.mkdir(parents=True, exist_ok=True)
    with LiveStudio(s, lead_s=LEAD_S, record=folder / "take.mcap") as live:
        _until_take(live, 2.5)
        killed = live.kill("mocapd")
        restarted = live.restart("mocapd")
        first = live.wait(_pose(live, restarted), WAIT_S, "a pose from the restarted mocapd")
        _until_take(live, live.take_s(first.message.capture_time_ns) + 3.0)
    poses = live.poses()
    before = [a.message for a in poses if a.time_ns < killed]
    after = [a.message for a in poses if a.message.capture_time_ns > first.message.capture_time_ns + 1e9]
    errors = [score(s, Run(p, [], {}, live.start_ns)).get("joint_centres_pos_cm") for p in (before, after)]
    return {"drill": "host", "resume_s": (first.time_ns - restarted) * 1e-9,
            "imus_after": int(np.median([len(p.imus) + len(p.imus_distrusted) for p in after])),
            "joint_centres_cm_before": errors[0], "joint_centres_cm_after": errors[1],
            "down_s": (first.time_ns - killed) * 1e-9}


def clock(s: Studio, folder: Path) -> dict:
    """The clock drill: STEPPED's clock off by +1 s from 2 to 3 s, by -1 s from 4 to 5 s."""
    folder.mkdir(parents=True, exist_ok=True)
    steps = [a for at, off in CLOCK_STEPS for a in ("--clock-step", str(at), str(off))]
    with LiveStudio(s, lead_s=LEAD_S, record=folder / "take.mcap", camera_args={STEPPED: steps}) as live:
        counted = live.wait(_health(0, f"camera/{STEPPED}", lambda x: x.clock_steps >= len(CLOCK_STEPS)),
                            live.lead_s + CLOCK_STEPS[-1][0] + WAIT_S, "Health: the four clock steps")
        _until_take(live, CLOCK_STEPS[-1][0] + 1.5)
    first_count = next(a for a in live.healths() for x in a.message.streams
                       if x.stream == f"camera/{STEPPED}" and x.clock_steps > 0)
    stream = next(x for x in live.healths()[-1].message.streams if x.stream == f"camera/{STEPPED}")
    poses = sorted((a.message for a in live.poses()), key=lambda p: p.capture_time_ns)
    t = np.array([live.take_s(p.capture_time_ns) for p in poses])
    with_box = np.array([STEPPED in p.cameras for p in poses])
    latency = np.array([p.latency_ms for p in poses])
    (a, _), (b, _), (c, _), (d, _) = CLOCK_STEPS
    off = ((t >= a + 0.1) & (t < b)) | ((t >= c + 0.1) & (t < d))
    on = (t > a - 1.0) & (t < a - 0.1) | (t > b + 0.5) & (t < c - 0.1) | (t > d + 0.5)
    back = [float(t[(t >= at) & with_box].min() - at) for at, o in CLOCK_STEPS if o == 0.0]
    return {"drill": "clock", "clock_steps": stream.clock_steps, "dropped": stream.dropped,
            "noticed_after_s": live.take_s(first_count.time_ns) - CLOCK_STEPS[0][0],
            "counted_all_after_s": live.take_s(counted.time_ns) - CLOCK_STEPS[-1][0],
            "frames_skipped": int(np.maximum(np.round(np.diff(t) / PERIOD_S) - 1, 0).sum()),
            "box_used_while_off": float(with_box[off].mean()), "box_used_while_on": float(with_box[on].mean()),
            "back_after_s": back, "latency_p99_ms_off": float(np.percentile(latency[off], 99)),
            "latency_p99_ms_on": float(np.percentile(latency[on], 99))}


def bench() -> list[dict]:
    """The `drill` benchmark lines: the three drills on one studio."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        s = studio(folder / "studio")
        return [_rounded(d(s, folder / d.__name__)) for d in (edge, host, clock)]


def _rounded(x):
    if isinstance(x, dict):
        return {k: _rounded(v) for k, v in x.items() if not k.endswith("_ns")}
    if isinstance(x, list):
        return [_rounded(v) for v in x]
    return round(x, 3) if isinstance(x, float) else x
