"""`mocap solve --take DIR --out OUTDIR`: a take folder (docs/take_format.md) solved
without oracles. Done so far: the subject chosen per camera and frame, its skeleton
estimated from the first seconds (mocap.calibration.skeleton), a video-only solve of every
frame (E_P and the prior). Not yet: the IMUs' mounting, heading and position (issue 6), so a
take's IMU files are read and checked but not used — the report says so.

Writes OUTDIR/joints.csv (frame, time_s, then <joint>_x, _y, _z in metres in the take's
world frame: joint centres of the solved skeleton), OUTDIR/take.bvh and
OUTDIR/calibration.json + calibration.md (what was estimated, from how many frames).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from mocap import _core, paths
from mocap.calibration import skeleton as skeleton_estimate
from mocap.errors import InputError
from mocap.export.bvh import write_bvh
from mocap.joint_centres import JOINTS, bone_indices
from mocap.solver import Solver
from mocap.take_folder import TakeFolder, read_take
from mocap_edge.detect.openpose_json import box_size

SKELETON_SECONDS = 5.0  # the first seconds the skeleton is estimated from



def subject(take: TakeFolder) -> np.ndarray:
    """(F, C, K, 3) the subject's keypoints (zeros where a camera saw nobody): per camera, the
    person nearest the previous frame's choice, the largest one to start with or after a gap."""
    cams, k = len(take.people), {"coco17": 17, "body25b": 25, "blazepose33": 33}[take.layout]
    out = np.zeros((take.n_frames, cams, k, 3))
    for c in range(cams):
        previous = None
        for f, people in enumerate(take.people[c]):
            if len(people) == 0:
                previous = None
                continue
            if previous is None:
                chosen = max(people, key=box_size)
            else:
                def distance(p):
                    both = (p[:, 2] > 0) & (previous[:, 2] > 0)
                    return np.median(np.linalg.norm(p[both, :2] - previous[both, :2], axis=1)) if both.any() else np.inf
                chosen = min(people, key=distance)
            out[f, c] = previous = chosen
    return out


def solve_take(folder: Path, out: Path) -> dict:
    take = read_take(folder)
    if take.rig is None:
        raise InputError(f"{folder}: the take has no video; an IMU-only solve needs the IMU calibration (not yet)")
    det = subject(take)
    first = det[: max(1, int(SKELETON_SECONDS * take.frame_rate))]
    estimate = skeleton_estimate.estimate(take.rig, first, take.layout)
    skel = estimate.skeleton
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / f"{take.layout}.json"), skel).scaled_to(skel)
    solver = Solver(skel, take.rig, layout, [])
    thetas, statuses = [], []
    for f in range(take.n_frames):
        cams = [c for c in range(det.shape[1]) if (det[f, c, :, 2] > 0).any()]
        r = solver.solve(f / take.frame_rate, cams, det[f, cams], [], np.zeros((0, 4)), np.zeros((0, 3)))
        thetas.append(np.array(r.theta))
        statuses.append(str(r.status))
    thetas = np.array(thetas)
    out.mkdir(parents=True, exist_ok=True)
    _write_joints(out / "joints.csv", skel, thetas, take)
    write_bvh(out / "take.bvh", skel, thetas, take.frame_rate)
    report = {"frames": take.n_frames, "frame_rate": take.frame_rate, "cameras": len(take.rig.cameras),
              "layout": take.layout, "skeleton": {"from_frames": len(first), "scales": estimate.scales,
                                                  "lengths_m": estimate.lengths_m, "frames_per_length": estimate.frames},
              "imus": {"sensors": [i.sensor for i in take.imus],
                       "used": False, "why": "IMU mounting, heading and position are not estimated yet (issue 6)"},
              "solve": {"statuses": {s: statuses.count(s) for s in set(statuses)}}}
    (out / "calibration.json").write_text(json.dumps(report, indent=1))
    (out / "skeleton.json").write_text(skel.to_json())
    (out / "calibration.md").write_text(_markdown(report))
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


def _markdown(r: dict) -> str:
    rows = "\n".join(f"| {g} | {s:.3f} | {100 * r['skeleton']['lengths_m'][g]:.1f} cm | {r['skeleton']['frames_per_length'][g]} |"
                     if g in r["skeleton"]["lengths_m"] else f"| {g} | {s:.3f} | (overall scale) | 0 |"
                     for g, s in r["skeleton"]["scales"].items())
    return "\n".join([
        "# Calibration report", "",
        f"Skeleton: estimated from the first {r['skeleton']['from_frames']} frames (triangulated keypoints,",
        "median distances, left and right pooled), as scales of the default skeleton's bone groups:", "",
        "| group | scale | measured | distances |", "|---|---|---|---|", rows, "",
        f"IMUs: {', '.join(r['imus']['sensors']) or 'none'} — not used: {r['imus']['why']}.", "",
        f"Solve: {r['frames']} frames, video only; statuses {r['solve']['statuses']}.", ""])
