"""Offline solve of a recording: the recorded inputs fed through the live host's own
pipeline (C++ HostPipeline: decode, synchronise, solve) in arrival order, with their
recorded arrival times — the result is what the live host would have published."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from mocap import _core
from mocap.errors import InputError
from mocap.net import wire
from mocap.recording import reader

FLUSH_NS = 1_000_000_000  # after the last input: frames still waiting are handed over


def solve_recording(path: Path, session: Path | None = None) -> tuple[list, dict, _core.Skeleton]:
    """PoseFrames of the recording's inputs (/camera/*, /imu/*, and the live calibrator's
    /calibration/*) solved with the session's skeleton, rig, layout and IMU set (by default
    the session attached to the recording), as calibrations came; the inputs dropped, by
    reason; and the skeleton in use at the end (the latest calibration's)."""
    if session is None:
        with tempfile.TemporaryDirectory() as folder:
            attached = reader.read_session(path, folder)
            if attached is None:
                raise InputError(f"{path}: no session is attached to this recording; give its session file")
            return solve_recording(path, attached)
    pipeline = _core.HostPipeline.load(str(session))
    poses, now = [], 0
    for m in reader.read(path):
        if not m.topic.startswith(("/camera/", "/imu/", "/calibration/")):
            continue
        now = m.log_time_ns
        pipeline.feed(m.type_name.encode(), m.payload, now)
        poses += [wire.PoseFrame.FromString(p) for p, _ in pipeline.solve(now)]
    poses += [wire.PoseFrame.FromString(p) for p, _ in pipeline.solve(now + FLUSH_NS)]
    return poses, dict(pipeline.dropped), pipeline.skeleton


def joint_positions(poses: list) -> np.ndarray:
    """(F, J, 3) m: the bone origins as the host published them (PoseFrame.joints), each
    frame with the calibration it was solved with."""
    return np.array([[[j.px, j.py, j.pz] for j in p.joints] for p in poses])


def frame_rate(poses: list) -> float:
    """The take's frame rate from the solved frames' capture times."""
    if len(poses) < 2:
        return 60.0
    return float(1e9 / np.median(np.diff([p.capture_time_ns for p in poses])))
