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
from mocap.errors import InputError
from mocap.export.bvh import write_bvh
from mocap.joint_centres import JOINTS, bone_indices
from mocap.solver import Solver, imu_set_json, layout_json
from mocap.take_folder import TakeFolder, read_take
from mocap_edge.detect.openpose_json import box_size

LAYOUT_SIZES = {"coco17": 17, "body25b": 25, "blazepose33": 33}


def subject(take: TakeFolder) -> np.ndarray:
    """(F, C, K, 3) the subject's keypoints of a take (choose_subject)."""
    return choose_subject(take.people, take.n_frames, LAYOUT_SIZES[take.layout])


def choose_subject(people: list, n_frames: int, k: int) -> np.ndarray:
    """(F, C, K, 3) the subject's keypoints from people[camera][frame] (P, K, 3) (zeros where a
    camera saw nobody): per camera, the person nearest the previous frame's choice, the
    largest one to start with or after a gap."""
    out = np.zeros((n_frames, len(people), k, 3))
    for c, frames in enumerate(people):
        previous = None
        for f, persons in enumerate(frames):
            if len(persons) == 0:
                previous = None
                continue
            if previous is None:
                chosen = max(persons, key=box_size)
            else:
                def distance(p):
                    both = (p[:, 2] > 0) & (previous[:, 2] > 0)
                    return np.median(np.linalg.norm(p[both, :2] - previous[both, :2], axis=1)) if both.any() else np.inf
                chosen = min(persons, key=distance)
            out[f, c] = previous = chosen
    return out


def solve_take(folder: Path, out: Path) -> dict:
    take = read_take(folder)
    if take.rig is None:
        raise InputError(f"{folder}: the take has no video; an IMU-only solve needs the IMU calibration from video")
    det = subject(take)
    times = np.arange(take.n_frames) / take.frame_rate
    bones = _core.Skeleton.load(str(paths.DEFAULT_SKELETON)).bone_names
    readings = window.readings_at(times, [(m.sensor, bones.index(m.bone), m.times_s, m.quaternions, m.accelerations)
                                          for m in take.imus]) if take.imus else None
    cal, score, why_not = informative.estimate(take.rig, det, times, take.layout, readings)
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
    w = r["window"]
    rows = "\n".join(f"| {g} | {s:.3f} | {100 * r['skeleton']['lengths_m'][g]:.1f} cm | {r['skeleton']['frames_per_length'][g]} |"
                     if g in r["skeleton"]["lengths_m"] else f"| {g} | {s:.3f} | (overall scale) | 0 |"
                     for g, s in r["skeleton"]["scales"].items())
    refined = ", ".join(f"{g} x{s:.3f}" for g, s in w["scales_window"].items())
    shifts = ", ".join(f"{g} ({', '.join(f'{100 * v:+.1f}' for v in d)}) cm" for g, d in w["shifts_window_m"].items())
    change = r["solve"]["heading_change_deg"]
    accel = lambda i: ("-" if i["heading_accelerometer_deg"] is None  # noqa: E731
                       else f"{i['heading_accelerometer_deg']:.1f} ± {i['heading_accelerometer_sigma_deg']:.1f}")
    imus = "\n".join(f"| {name} | {i['bone']} | {i['heading_deg']:.1f} | {accel(i)} | {change[name]:+.1f} | "
                     f"{i['first_residual_deg']:.1f} | "
                      f"{i['residual_deg']:.2f} | {', '.join(f'{100 * v:.1f}' for v in w['imu_positions'][name]['offset_m'])} | "
                      f"{'estimated' if w['imu_positions'][name]['estimated'] else 'usual place'} |"
                      for name, i in w["imus"].items())
    lines = [
        "# Calibration report", "",
        f"Skeleton, first estimate: {r['skeleton']['from_frames']} frames from {w['window_start_s']:.1f} s "
        "(triangulated keypoints,",
        "median distances, left and right pooled), as scales of the default skeleton's bone groups:", "",
        "| group | scale | measured | distances |", "|---|---|---|---|", rows, "",
        f"Window calibration ({w['frames']} frames of the {w['window_s']:.1f} s from {w['window_start_s']:.1f} s"
        f"{'' if r['window_motion_score_deg'] is None else ', IMUs tilting ' + format(r['window_motion_score_deg'], '.1f') + ' deg RMS'}"
        f", {w['iterations']} iterations, "
        f"cost {w['cost']['start']:.0f} -> {w['cost']['end']:.0f}):",
        f"lengths {refined}; shifts {shifts}. Keypoint sites: "
        f"{'estimated along ' + str(w['site_directions_kept']) + ' observed directions' if w['sites_estimated'] else 'the layout' + chr(39) + 's'}"
        f" (`layout.json`).",
        f"Calibration pose: {w['calibration_pose'] + '-pose held, ' + str(w['calibration_pose_frames']) + ' frames' if w['calibration_pose'] else 'none found'}.",
        ""]
    if w["imus"]:
        lines += ["Heading: from the window, with the accelerometer's (± its standard deviation) as a prior; change: "
                  "the heading tracking's correction at the take's end.", "",
                  "| sensor | bone | heading (deg) | accelerometer (deg) | change (deg) | start residual (deg) | "
                  "residual (deg) | offset (cm) | position |", "|---|---|---|---|---|---|---|---|---|", imus, ""]
    else:
        lines += [f"IMUs not used: {r['imus_not_used_because']}." if r["imus_not_used_because"]
                  else "No IMUs: a video-only solve.", ""]
    lines += [f"Solve: {r['frames']} frames, {r['imus_used']} IMUs; statuses {r['solve']['statuses']}.", ""]
    return "\n".join(lines)
