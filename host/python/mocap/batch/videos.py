"""A trial filmed, not yet detected, as Pose2Sim lays one out: TRIAL/videos/<camera>.mp4 and
its calibration in TRIAL/calibration/ or, for a batch of trials, in calibration/ beside them
(a Calib*.toml of Pose2Sim / anipose, or a Qualisys .qca.txt). The task detects every video
with the camera box's own detector (BlazePose with region tracking, one inference thread: a
worker uses one core) and writes the take folder the rest of the task solves."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mocap.errors import InputError
from mocap.io.video_rig import rig_for
from mocap.io.take_folder import LAYOUTS, TakeFolder, write_take
from mocap_edge.detect.base import open_detector
from mocap_edge.detect.video import detect_frames, open_tracker

VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv")
THREADS = 1
MAX_PEOPLE = 2  # tracked per camera; the host chooses the subject among them


def is_trial(folder: Path) -> bool:
    return folder.is_dir() and bool(videos(folder))


def videos(trial: Path) -> list[Path]:
    return sorted(p for p in (trial / "videos").glob("*") if p.suffix.lower() in VIDEO_SUFFIXES and p.is_file())


def calibration(trial: Path) -> Path:
    """The trial's calibration file: its own calibration/ folder first, then its batch's."""
    for folder in (trial / "calibration", trial.parent / "calibration"):
        found = sorted(folder.glob("*.toml")) + sorted(folder.glob("*.qca.txt"))
        if found:
            return found[0]
    raise InputError(f"{trial}: no calibration (a Calib*.toml or .qca.txt in {trial / 'calibration'} or "
                     f"{trial.parent / 'calibration'})")


def write_take_folder(trial: Path, out: Path) -> dict:
    """Detects the trial's videos into the take folder `out`; what was detected."""
    files = videos(trial)
    calib = calibration(trial)
    rig = rig_for(calib, [v.stem for v in files])
    tracker_layout, people, rates = None, [], set()
    model = open_detector("blazepose", threads=THREADS)  # loaded once; a tracker per video holds its regions
    for video in files:
        tracker = open_tracker(model, MAX_PEOPLE)
        frames = [(found, rate) for _, found, rate in detect_frames(video, tracker)]
        if not frames:
            raise InputError(f"{video}: no frame could be read")
        keypoints = len(tracker.model.layout.names)
        people.append([np.array(found).reshape(len(found), keypoints, 3) for found, _ in frames])
        rates.add(round(frames[0][1], 3))
        tracker_layout = tracker.model.layout.name
    n = min(len(p) for p in people)
    take = TakeFolder(frame_rate=float(min(rates)), n_frames=n, world_up="Z")
    take.rig, take.layout, take.people = rig, tracker_layout, [p[:n] for p in people]
    if tracker_layout not in LAYOUTS.values():
        raise InputError(f"the detector's layout {tracker_layout!r} has no take folder name")
    write_take(out, take)
    return {"videos": len(files), "calibration": str(calib), "frames": n, "frame_rate": take.frame_rate,
            "people_per_frame": float(np.mean([len(f) for p in people for f in p[:n]]))}
