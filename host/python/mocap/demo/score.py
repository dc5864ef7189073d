"""The poses a live run published, scored against the simulated truth (accuracy, latency,
frames that never came back), and the live benchmark."""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np

from mocap import rotations
from mocap.demo.play import LEAD_S, Run, play
from mocap.demo.studio import IMU_RATE, Studio, prepare
from mocap.eval import metrics
from mocap.model.solver import distrust_spans
from mocap.recording import offline

BOX_START_S = 0.5  # of the take's lead per camera box started (two cores)

KEYS = ("pos_error_cm", "ori_error_deg", "ori_error_offset_removed_deg", "vel_error_cms", "joint_centres_pos_cm",
        "joint_centres_vel_cms")


def score(studio: Studio, run: Run) -> dict:
    """Accuracy against the simulated truth, latency, and frames that never came back."""
    frame_ns = run.start_ns + np.round(studio.frame_times * 1e9).astype(np.int64)
    by_time = {p.capture_time_ns: p for p in run.poses}
    matched = [f for f, t in enumerate(frame_ns) if t in by_time]
    poses = [by_time[frame_ns[f]] for f in matched]
    latency = np.array([p.latency_ms for p in run.poses])
    solve = np.array([p.solve_time_ms for p in run.poses])
    out = {"frames": len(frame_ns), "solved": len(matched), "dropped": len(frame_ns) - len(matched),
           **_percentiles("latency", latency), **_percentiles("solve", solve),
           # what the host adds to a frame's own solve: synchronising, frames solved before it, building the pose
           **_percentiles("beside_solve", latency - solve),
           "host_dropped": run.host_summary.get("dropped", {}),
           # the host's heading tracking, as its last Health reported it (deg per IMU)
           "heading_corrections_deg": {s.stream.removeprefix("imu/"): s.heading_correction_deg
                                       for s in (run.healths[-1].streams if run.healths else [])
                                       if s.stream.startswith("imu/")}}
    if len(matched) > 2:
        out.update(_accuracy(studio, run, matched, poses))
    out["thetas"], out["times"] = np.array([list(p.theta) for p in poses]), studio.frame_times[matched]
    out["positions"] = offline.joint_positions(poses)  # (F, J, 3) as published
    return out


def _percentiles(name: str, ms: np.ndarray) -> dict:
    return {f"{name}_{k}_ms": (float(np.percentile(ms, q)) if len(ms) else None)
            for k, q in (("p50", 50), ("p99", 99), ("max", 100))}


def _accuracy(studio: Studio, run: Run, matched: list[int], poses: list) -> dict:
    """The bones as published (each frame with the calibration it was solved with) against the
    truth; with the live calibrator, its calibrations and the errors from the first on."""
    dt = float(np.median(np.diff(studio.frame_times)))
    positions = offline.joint_positions(poses)
    orientations = rotations.matrix_from_quaternion(np.array([[[j.qw, j.qx, j.qy, j.qz] for j in p.joints]
                                                              for p in poses]))
    e = metrics.transform_errors(studio.skeleton, studio.truth[matched], positions, orientations, dt)
    out = {k: e[k] for k in KEYS}
    history = studio.calibrated / "calibrations.jsonl"
    if history.is_file():  # the live calibrator's, at take times
        out["calibrations"] = [{**c, "take_s": (c["valid_from_ns"] - run.start_ns) * 1e-9}
                               for c in map(json.loads, history.read_text().splitlines())]
    out["distrusted"] = distrust_spans(studio.frame_times[matched], [list(p.imus_distrusted) for p in poses])
    with_imus = np.array([len(p.imus) > 0 for p in poses])
    if studio.calibration == "live" and with_imus.any():  # from the first calibration on
        first = int(np.argmax(with_imus))
        out["calibrated_from_s"] = float(studio.frame_times[matched[first]])
        if len(poses) - first > 2:
            e = metrics.transform_errors(studio.skeleton, studio.truth[matched[first:]], positions[first:],
                                         orientations[first:], dt)
            out["calibrated"] = {k: e[k] for k in KEYS}
    return out


def bench(seconds: float = 60.0, realtime: bool = True, cameras: int = 8, calibration: str | None = None) -> dict:
    """The live benchmark: `cameras` x 60 fps (33 keypoints) + 13 IMUs x 100 Hz over loopback
    for `seconds`; host latency and frames that never came back. realtime: mocapd asks for
    real-time scheduling (play.REALTIME_PRIORITY). calibration: the session's (studio.prepare's
    choices); by default "estimated" up to 8 cameras and the truth's ("oracle") beyond
    (estimating one first would replay every camera's take through the boxes' pieces; the
    host's work per frame is the same). Beyond 8 cameras the boxes get longer to start: one
    process each, each an interpreter importing numpy and ZeroMQ."""
    with tempfile.TemporaryDirectory() as folder:
        calibration = calibration or ("estimated" if cameras <= 8 else "oracle")
        studio = prepare(Path(folder), seconds, cameras=cameras, calibration=calibration)
        run = play(studio, realtime=realtime, lead_s=max(LEAD_S, BOX_START_S * cameras))
        result = score(studio, run)
    return {"bench": "live", "seconds": seconds, "cameras": len(studio.camera_ids), "imus": 13,
            "imu_rate_hz": IMU_RATE, **{k: v for k, v in result.items() if k.endswith("_ms")},
            "frames": result["frames"], "dropped": result["dropped"], "calibration": studio.calibration,
            "joint_centres_pos_cm": result.get("joint_centres_pos_cm"), "pos_error_cm": result.get("pos_error_cm"),
            "host_dropped_inputs": result["host_dropped"], "host_realtime": run.host_summary.get("realtime")}
