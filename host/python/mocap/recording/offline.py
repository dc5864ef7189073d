"""Offline solve of a recording (or of any timestamped messages: a take folder's): the
inputs fed through the live host's own pipeline (C++ HostPipeline: decode, synchronise,
solve) in arrival order, with their arrival times — the result is what the live host would
have published. The end of the messages is the end of the input: what is still pending is
released as the input path releases it (InputPath::Flush), and solved."""

from __future__ import annotations

import tempfile
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from mocap import _core
from mocap.errors import InputError
from mocap.io.bvh_export import write_bvh
from mocap.io.joints_csv import write_positions_csv
from mocap.net import wire
from mocap.recording import published, reader

INPUT_TOPICS = ("/camera/", "/imu/", "/calibration/")


def solve_recording(recording: Path | reader.Recording, session: Path | None = None) -> tuple[list, dict, _core.Skeleton]:
    """PoseFrames of the recording's inputs (/camera/*, /imu/*, and the live calibrator's
    /calibration/*) solved with the session's skeleton, rig, layout and IMU set (by default
    the session attached to the recording), as calibrations came; the inputs dropped, by
    reason; and the skeleton in use at the end (the latest calibration's). A recording cut
    short or damaged gives what its intact chunks hold (its Integrity says what is lost)."""
    if not isinstance(recording, reader.Recording):  # a path
        with reader.Recording(recording) as opened:
            return solve_recording(opened, session)
    if session is None:
        with tempfile.TemporaryDirectory() as folder:
            attached = recording.session(folder)
            if attached is None:
                raise InputError(f"{recording.path}: no session is attached to this recording; give its session file")
            return solve_recording(recording, attached)
    messages = ((m.log_time_ns, m.type_name, m.payload) for m in recording.messages()
                if m.topic.startswith(INPUT_TOPICS))
    pipeline = pipeline_for(session)
    return solve_messages(pipeline, messages), dict(pipeline.dropped), pipeline.skeleton


def pipeline_for(session: Path) -> _core.HostPipeline:
    """The live host's pipeline for `session`; InputError when mocapd would refuse it."""
    try:
        return _core.HostPipeline.load(str(session))
    except ValueError as e:
        raise InputError(f"{session}: {e}") from None


def solve_messages(pipeline: _core.HostPipeline, messages: Iterable[tuple[int, str, bytes]]) -> list:
    """PoseFrames of (arrival ns, type name, payload) messages in arrival order, solved by
    `pipeline` as they come; the end of the messages is the end of the input. What the
    pipeline drops is counted in pipeline.dropped."""
    poses = []
    for arrival_ns, type_name, payload in messages:
        pipeline.feed(type_name.encode(), payload, arrival_ns)
        poses += [wire.PoseFrame.FromString(p) for p, _ in pipeline.solve(arrival_ns)]
    return poses + [wire.PoseFrame.FromString(p) for p, _ in pipeline.flush()]


def joint_positions(poses: list) -> np.ndarray:
    """(F, J, 3) m: the bone origins as the host published them (PoseFrame.joints), each
    frame with the calibration it was solved with."""
    return np.array([[[j.px, j.py, j.pz] for j in p.joints] for p in poses])


def frame_rate(poses: list) -> float:
    """The take's frame rate from the solved frames' capture times."""
    if len(poses) < 2:
        return 60.0
    return float(1e9 / np.median(np.diff([p.capture_time_ns for p in poses])))


def write_poses(poses: list, skeleton: _core.Skeleton, bvh: Path, csv: Path | None = None, suits: list = ()) -> list:
    """The solved poses as a BVH of `skeleton` (the latest calibration's) and, if csv, the joint
    positions as solved, each frame with the calibration in use then (mocap.io.joints_csv).
    Poses of several people: a BVH (and CSV) per person, the name with _subjectN before its
    suffix, each of the skeleton of the suit they wore last (suits: published.suit_skeletons)
    else `skeleton`, the CSVs' times all from the take's first pose. The files written."""
    subjects = sorted({p.subject_id for p in poses})
    if subjects == [0]:
        return _write_person(poses, skeleton, bvh, csv)
    written, start_ns = [], min(p.capture_time_ns for p in poses)
    for subject in subjects:
        person = [p for p in poses if p.subject_id == subject]
        written += _write_person(person, published.worn_skeleton(person, suits, skeleton),
                                 published.subject_file(bvh, subject), csv and published.subject_file(csv, subject),
                                 start_ns)
    return written


def _write_person(poses: list, skeleton: _core.Skeleton, bvh: Path, csv: Path | None,
                  start_ns: int | None = None) -> list:
    """One person's BVH and CSV, the CSV's times from start_ns (default: their first pose)."""
    write_bvh(bvh, skeleton, np.array([list(p.theta) for p in poses]), frame_rate(poses))
    if csv is None:
        return [bvh]
    start_ns = poses[0].capture_time_ns if start_ns is None else start_ns
    times = np.array([p.capture_time_ns - start_ns for p in poses]) * 1e-9
    write_positions_csv(csv, skeleton.bone_names, joint_positions(poses), times)
    return [bvh, csv]
