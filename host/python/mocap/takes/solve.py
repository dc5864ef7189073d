"""`mocap solve --take DIR --out OUTDIR`: a take folder (docs/take_format.md) solved
without oracles: the subject chosen per camera and frame, the calibration estimated from
the take's first 5 s with enough motion (mocap.calibration.informative: where the IMUs
tilt; the first 5 s without IMUs) by mocap.calibration.window (skeleton, keypoint sites, IMU
mountings, headings and positions), then every frame solved with the IMUs (E_R, E_P, E_A and
the prior), or video only when the take has no IMUs or they never move enough to calibrate.

Writes OUTDIR/joints.csv (frame, time_s, then <joint>_x, _y, _z in metres in the take's
world frame: joint centres of the solved skeleton), OUTDIR/take.bvh, OUTDIR/skeleton.json and
OUTDIR/imus.json (the estimated skeleton and IMU sites in the solver's formats) and
OUTDIR/calibration.json + calibration.md (what was estimated, from how many frames).
"""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from mocap import _core, paths
from mocap.calibration import informative, window
from mocap.calibration.calibration_input import CalibrationInput
from mocap.calibration.readings import readings_at
from mocap.errors import InputError
from mocap.io.bvh_export import write_bvh
from mocap.io.take_folder import TakeFolder, read_take
from mocap.model.joint_centres import JOINTS, bone_indices
from mocap.model.solver import Solver, imu_set_json, layout_json
from mocap.model.subject import LAYOUT_SIZES, choose_subject
from mocap.takes.report import markdown


def subject(take: TakeFolder) -> np.ndarray:
    """(F, C, K, 3) the subject's keypoints of a take (mocap.model.subject.choose_subject)."""
    return choose_subject(take.people, take.n_frames, LAYOUT_SIZES[take.layout])


def solve_take(folder: Path, out: Path) -> dict:
    take = read_take(folder)
    if take.rig is None:
        raise InputError(f"{folder}: the take has no video; an IMU-only solve needs the IMU calibration from video")
    det = subject(take)
    times = np.arange(take.n_frames) / take.frame_rate
    bones = _core.Skeleton.load(str(paths.DEFAULT_SKELETON)).bone_names
    readings = readings_at(times, [(m.sensor, bones.index(m.bone), m.times_s, m.quaternions, m.accelerations)
                                   for m in take.imus]) if take.imus else None
    cal, score, why_not = informative.estimate(take.rig, CalibrationInput.from_arrays(det, times, take.layout,
                                                                                      readings))
    if why_not:
        readings = None
    solver = Solver(cal.skeleton, take.rig, cal.layout, cal.imus, options=window.solver_options())
    thetas, statuses = window.solve_frames(solver, det, times, readings)
    out.mkdir(parents=True, exist_ok=True)
    _write_joints(out / "joints.csv", cal.skeleton, thetas, take)
    write_bvh(out / "take.bvh", cal.skeleton, thetas, take.frame_rate)
    start = cal.skeleton_start
    report = {"frames": take.n_frames, "frame_rate": take.frame_rate, "cameras": len(take.rig.cameras),
              "layout": take.layout, "imus_used": len(cal.imus), "imus_not_used_because": why_not,
              "window_motion_score_deg": score,
              "skeleton": {"from_frames": int(np.diff(np.searchsorted(times, times[0] + cal.report["window_start_s"]
                                                                      + np.array([0.0, window.SECONDS])))[0]),
                           "scales": start.scales,
                           "lengths_m": start.lengths_m, "frames_per_length": start.frames},
              "window": cal.report, "solve": {"statuses": {s: statuses.count(s) for s in set(statuses)},
                                              # the heading tracking's correction at the take's end
                                              "heading_change_deg": {s.name: float(np.degrees(h)) for s, h in
                                                                     zip(cal.imus, solver.headings)}}}
    (out / "calibration.json").write_text(json.dumps(report, indent=1))
    (out / "skeleton.json").write_text(cal.skeleton.to_json())
    (out / "imus.json").write_text(json.dumps(imu_set_json(cal.skeleton, cal.imus), indent=1))
    (out / "layout.json").write_text(json.dumps(layout_json(cal.skeleton, cal.layout), indent=1))
    (out / "calibration.md").write_text(markdown(report))
    return report


def _write_joints(path: Path, skel: _core.Skeleton, thetas: np.ndarray, take: TakeFolder) -> None:
    bones = bone_indices(skel.bone_names)
    back = take.world_from_take.T  # ours -> the take's world
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["frame", "time_s", *[f"{j}_{a}" for j in JOINTS for a in "xyz"]])
        for i, theta in enumerate(thetas):
            _, pos = skel.forward_kinematics(theta)
            p = pos[bones] @ back.T
            w.writerow([i, f"{i / take.frame_rate:.6f}", *[f"{v:.6f}" for v in p.reshape(-1)]])
