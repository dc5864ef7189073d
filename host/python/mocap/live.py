"""The running system on one machine: the simulated studio played in real time by edge
processes over ZeroMQ on loopback — one camera box per camera (`python -m mocap_edge camera
--source sim:STREAMS`: the box's own loop on the simulated backend) and the IMU hub — the
C++ host `mocapd` solving live, and a consumer collecting PoseFrame and Health (progress,
outputs, report).

`mocap demo` and the live benchmark are this with different lengths and outputs.
"""

from __future__ import annotations

import dataclasses
import json
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import zmq

from mocap import _core, demo_motion, offline, paths, recording, rotations, transport, wire
from mocap.calibration import informative, window
from mocap.errors import InputError
from mocap.sim import take as sim_take
from mocap.solver import imu_set_json, layout_json
from mocap_edge.streams import Streams

MOCAPD = paths.REPO / "build" / "host" / "mocapd"
LEAD_S = 4.0  # between launching the processes and the take's first frame
IMU_RATE = 100.0


@dataclasses.dataclass
class Studio:
    """A simulated take ready to be played: its session folder and truth."""
    session: Path
    streams: Path
    skeleton: _core.Skeleton  # the truth's
    truth: np.ndarray  # (F, 66) at the frame times
    frame_times: np.ndarray  # (F,) s, as the cameras report them
    camera_ids: list[str]
    endpoints: dict[str, str]  # "cam0".. "hub0", "host" -> endpoint
    session_skeleton: _core.Skeleton  # the session's: estimated, the truth's (oracle), the default's (live)
    calibration: str  # "estimated", "oracle" or "live"
    calibrator: str | None = None  # live: the calibrator's endpoint (its sessions in `calibrated`)
    detect_every: tuple[int, int] = (1, 1)  # the cameras' (period, burst): high-speed mode when period > 1

    @property
    def calibrated(self) -> Path:
        """Where the live calibrator writes the session of its latest calibration."""
        return self.session.parent / "calibrated"


def calibrate(streams: Streams, rig: _core.Rig, imu_bones: list[int]) -> window.Calibration:
    """The calibration from the first seconds with motion of the streams, as `mocap calibrate`
    makes a studio's session (mocap.calibration.window, informative): nothing of the truth."""
    keypoints = np.where(streams.detected[:, None, None, None], streams.keypoints, 0.0).astype(float)
    times = streams.frame_times_ns * 1e-9
    imu_times = streams.imu_times_ns * 1e-9
    readings = window.readings_at(times, [(name, bone, imu_times, streams.imu_quaternions[:, i],
                                           streams.imu_accelerations[:, i])
                                          for i, (name, bone) in enumerate(zip(streams.imu_ids, imu_bones))])
    return informative.estimate(rig, keypoints, times, streams.layout, readings, detected=streams.detected)[0]


def free_ports(n: int) -> list[int]:
    socks = [socket.socket() for _ in range(n)]
    for s in socks:
        s.bind(("127.0.0.1", 0))
    ports = [s.getsockname()[1] for s in socks]
    for s in socks:
        s.close()
    return ports


def prepare(folder: Path, seconds: float, preset: str = "hq13", cameras: int | None = None, seed: int = 0,
            calibration: str = "estimated", still_s: float = 0.0) -> Studio:
    """Simulates `seconds` of the demo motion (after standing still for still_s, if given)
    and writes the session (skeleton, told rig, IMU set, layout, prior, endpoints) and the
    stream file into `folder`. The skeleton and the IMUs' mounting, heading and position are
    estimated from the streams' first seconds with motion before the take (`calibrate`), the
    truth's with calibration="oracle", or, with "live", estimated during the take by the live
    calibrator (mocap.calibrator; the session starts with the default skeleton and its IMUs
    uncalibrated)."""
    if calibration not in ("estimated", "oracle", "live"):
        raise InputError(f"calibration is 'estimated', 'oracle' or 'live', not {calibration!r}")
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    skeleton, thetas, dt = demo_motion.load_motion(60.0, seconds)
    if still_s > 0:
        thetas = demo_motion.after_held_pose(thetas, thetas[min(len(thetas) - 1, round(3.0 / dt))], dt, still_s)
    config = sim_take.Config(preset=preset, cameras=cameras)
    t = sim_take.simulate_motion(skeleton, thetas, dt, config, rng)
    # The IMUs sample at their own rate (the take's readings are at frame times).
    imu_times = np.arange(0.0, (len(thetas) - 1) * dt, 1.0 / IMU_RATE)
    quats, accs = sim_take.imu_readings(skeleton, t.imus, demo_motion.interpolate(thetas, imu_times / dt),
                                        imu_times, config, rng)
    n_kp = len(t.layout)
    keypoints = np.zeros((len(thetas), len(t.rig.cameras), n_kp, 3), np.float32)
    detected = np.array([k is not None for k in t.keypoints])
    for f, k in enumerate(t.keypoints):
        if k is not None:
            keypoints[f] = k
    camera_ids = [c.name for c in t.rig.cameras]
    streams = Streams(camera_ids, t.layout.name, np.array([[c.width, c.height] for c in t.rig.cameras]),
                      np.round(t.times * 1e9).astype(np.int64), keypoints, detected, [s.name for s in t.imus],
                      np.round(imu_times * 1e9).astype(np.int64), quats, accs)
    streams.save(folder / "streams.npz")
    ports = free_ports(len(camera_ids) + 3)
    endpoints = {c: f"tcp://127.0.0.1:{p}" for c, p in zip([*camera_ids, "hub0", "host", "calibrator"], ports)}
    session_skeleton, imus, layout = skeleton, t.imus, str(paths.LAYOUTS / f"{t.layout.name}.json")
    if calibration == "estimated":
        cal = calibrate(streams, t.rig, [s.bone for s in t.imus])
        session_skeleton, imus, layout = cal.skeleton, cal.imus, "layout.json"
        (folder / "calibration.json").write_text(json.dumps(cal.report, indent=1))
        (folder / "layout.json").write_text(json.dumps(layout_json(cal.skeleton, cal.layout), indent=1))
    elif calibration == "live":  # what a studio knows before the performer moves: the IMU set's bones
        session_skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
        imus = _core.load_imu_sites(str(paths.IMU_SETS[sim_take.PRESETS[preset].imus]), session_skeleton)
    (folder / "skeleton.json").write_text(session_skeleton.to_json())
    (folder / "rig.json").write_text(t.rig.to_json())
    (folder / "imus.json").write_text(json.dumps(imu_set_json(session_skeleton, imus), indent=1))
    session = {"format": "mocap.session/1", "skeleton": "skeleton.json", "rig": "rig.json", "imus": "imus.json",
               "layout": layout, "prior": str(paths.HOST_DATA / "prior_default.json"),
               "inputs": [endpoints[c] for c in [*camera_ids, "hub0"]], "output": endpoints["host"]}
    if calibration != "oracle":
        session["solver"] = {"heading_time_constant": window.HEADING_TIME_CONSTANT_S}
    if calibration == "live":
        session["inputs"].append(endpoints["calibrator"])
        session["imus_calibrated"] = False
    (folder / "session.json").write_text(json.dumps(session, indent=1))
    return Studio(folder / "session.json", folder / "streams.npz", skeleton, thetas, t.times, camera_ids,
                  {k: v for k, v in endpoints.items() if k != "calibrator"}, session_skeleton, calibration,
                  endpoints["calibrator"] if calibration == "live" else None,
                  (sim_take.PRESETS[preset].period, sim_take.PRESETS[preset].burst))


def camera_box_command(studio: Studio, c: int, start_ns: int, unplugged: tuple | None = None) -> list[str]:
    """The camera box of camera c on the simulated backend (its detection latency seeded by
    c); unplugged (camera id, from_s, to_s): that box is unplugged during the span."""
    camera = studio.camera_ids[c]
    cmd = [sys.executable, "-m", "mocap_edge", "camera", "--source", f"sim:{studio.streams}", "--camera", camera,
           "--bind", studio.endpoints[camera], "--start-ns", str(start_ns), "--seed", str(c)]
    if studio.detect_every[0] > 1:
        cmd += ["--hs", *map(str, studio.detect_every)]
    if unplugged and unplugged[0] == camera:
        cmd += ["--stop", *map(str, unplugged[1:])]
    return cmd


@dataclasses.dataclass
class Run:
    poses: list  # PoseFrame messages in arrival order
    healths: list
    host_summary: dict
    start_ns: int


def play(studio: Studio, progress=None, faults: dict | None = None, on_pose=None, record: Path | None = None) -> Run:
    """Plays the studio live: mocapd + one process per camera + the IMU hub, all on
    loopback, until the take ends. progress(health) is called once a second; on_pose(pose)
    for every PoseFrame. faults: {"camera": (id, from_s, to_s), "imu": (id, from_s, to_s)}."""
    if not MOCAPD.exists():
        raise InputError(f"{MOCAPD} is missing: run `make build`")
    faults = faults or {}
    duration = float(studio.frame_times[-1])
    start_ns = time.time_ns() + int(LEAD_S * 1e9)
    host = subprocess.Popen([str(MOCAPD), str(studio.session), "--duration", f"{LEAD_S + duration + 1.5:.3f}",
                             "--quiet"], stdout=subprocess.PIPE, text=True)
    edge = [subprocess.Popen(camera_box_command(studio, c, start_ns, faults.get("camera")))
            for c in range(len(studio.camera_ids))]
    cmd = [sys.executable, "-m", "mocap_edge", "imu-hub", "--streams", str(studio.streams),
           "--bind", studio.endpoints["hub0"], "--start-ns", str(start_ns)]
    if "imu" in faults:
        cmd += ["--stop-sensor", faults["imu"][0], "--stop", *map(str, faults["imu"][1:])]
    edge.append(subprocess.Popen(cmd))
    if studio.calibrator:  # the live calibrator, beside mocapd
        edge_endpoints = [studio.endpoints[c] for c in [*studio.camera_ids, "hub0"]]
        edge.append(subprocess.Popen([sys.executable, "-m", "mocap.cli", "calibrate", "--connect", *edge_endpoints,
                                      "--session", str(studio.session), "--out", str(studio.calibrated), "--follow",
                                      "--publish", studio.calibrator, "--duration", f"{LEAD_S + duration + 1.0:.3f}"]))
    recorder, stop = None, threading.Event()
    if record:
        inputs = [*studio.endpoints.values(), *([studio.calibrator] if studio.calibrator else [])]
        recorder = threading.Thread(target=recording.record, args=(inputs, record),
                                    kwargs={"stop": stop, "session": studio.session}, daemon=True)
        recorder.start()
    context = zmq.Context.instance()
    sub = transport.subscriber(context, [studio.endpoints["host"]])
    poses, healths = [], []
    try:
        while host.poll() is None:
            if not sub.poll(200):
                continue
            while True:
                try:
                    frames = sub.recv_multipart(zmq.NOBLOCK)
                except zmq.Again:
                    break
                try:
                    msg = wire.decode(frames)
                except wire.WireError:
                    continue
                if isinstance(msg, wire.PoseFrame):
                    poses.append(msg)
                    if on_pose:
                        on_pose(msg)
                elif isinstance(msg, wire.Health):
                    healths.append(msg)
                    if progress:
                        progress(msg)
        lines = host.stdout.read().strip().splitlines()
        if host.wait() != 0 or not lines:
            raise InputError(f"mocapd stopped with status {host.returncode} (its log is above)")
        summary = json.loads(lines[-1])
    finally:
        for p in [*edge, host]:
            if p.poll() is None:
                p.terminate()
            p.wait(timeout=10)
        sub.close()
        stop.set()
        if recorder:
            recorder.join(timeout=10)
    return Run(poses, healths, summary, start_ns)


def score(studio: Studio, run: Run) -> dict:
    """Accuracy against the simulated truth, latency, and frames that never came back."""
    from mocap import eval as evaluation

    frame_ns = run.start_ns + np.round(studio.frame_times * 1e9).astype(np.int64)
    by_time = {p.capture_time_ns: p for p in run.poses}
    matched = [f for f, t in enumerate(frame_ns) if t in by_time]
    poses = [by_time[frame_ns[f]] for f in matched]
    solved = np.array([list(p.theta) for p in poses])
    latency = np.array([p.latency_ms for p in run.poses])
    out = {"frames": len(frame_ns), "solved": len(matched), "dropped": len(frame_ns) - len(matched),
           "latency_p50_ms": float(np.percentile(latency, 50)) if len(latency) else None,
           "latency_p99_ms": float(np.percentile(latency, 99)) if len(latency) else None,
           "latency_max_ms": float(latency.max()) if len(latency) else None,
           "host_dropped": run.host_summary.get("dropped", {}),
           # the host's heading tracking, as its last Health reported it (deg per IMU)
           "heading_corrections_deg": {s.stream.removeprefix("imu/"): s.heading_correction_deg
                                       for s in (run.healths[-1].streams if run.healths else [])
                                       if s.stream.startswith("imu/")}}
    keys = ("pos_error_cm", "ori_error_deg", "vel_error_cms", "joint_centres_pos_cm", "joint_centres_vel_cms")
    dt = float(np.median(np.diff(studio.frame_times)))
    if len(matched) > 2:  # the bones as published: each frame with the calibration it was solved with
        positions = offline.joint_positions(poses)
        orientations = rotations.matrix_from_quaternion(np.array([[[j.qw, j.qx, j.qy, j.qz] for j in p.joints]
                                                                  for p in poses]))
        e = evaluation.transform_errors(studio.skeleton, studio.truth[matched], positions, orientations, dt)
        out.update({k: e[k] for k in keys})
        history = studio.calibrated / "calibrations.jsonl"
        if history.is_file():  # the live calibrator's, at take times
            out["calibrations"] = [{**c, "take_s": (c["valid_from_ns"] - run.start_ns) * 1e-9}
                                   for c in map(json.loads, history.read_text().splitlines())]
        with_imus = np.array([len(p.imus) > 0 for p in poses])
        if studio.calibration == "live" and with_imus.any():  # from the first calibration on
            first = int(np.argmax(with_imus))
            out["calibrated_from_s"] = float(studio.frame_times[matched[first]])
            if len(poses) - first > 2:
                e = evaluation.transform_errors(studio.skeleton, studio.truth[matched[first:]], positions[first:],
                                                orientations[first:], dt)
                out["calibrated"] = {k: e[k] for k in keys}
    out["thetas"], out["times"] = solved, studio.frame_times[matched]
    out["positions"] = offline.joint_positions(poses)  # (F, J, 3) as published
    return out


def bench(seconds: float = 60.0) -> dict:
    """The live benchmark: 8 cameras x 60 fps + 13 IMUs x 100 Hz over loopback for
    `seconds`; host latency and frames that never came back."""
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        studio = prepare(Path(folder), seconds)
        result = score(studio, play(studio))
    return {"bench": "live", "seconds": seconds, "cameras": len(studio.camera_ids), "imus": 13,
            "imu_rate_hz": IMU_RATE, "latency_p50_ms": result["latency_p50_ms"],
            "latency_p99_ms": result["latency_p99_ms"], "latency_max_ms": result["latency_max_ms"],
            "frames": result["frames"], "dropped": result["dropped"], "calibration": studio.calibration,
            "joint_centres_pos_cm": result.get("joint_centres_pos_cm"), "pos_error_cm": result.get("pos_error_cm"),
            "host_dropped_inputs": result["host_dropped"]}
