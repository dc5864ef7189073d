"""Video-only solve of the real Balancing trial (mocap.io.demo_data.fetch_trial): the edge
detector's BlazePose keypoints of the four real cameras, the shipped Qualisys calibration,
the host solver (E_P and the prior; no IMUs in this trial), compared with Pose2Sim's own
triangulated result (its TRC).

Skeleton: fitted to Pose2Sim's TRC (mocap.sim.demo_motion.body_model) — the subject's own
proportions, taken from the reference (estimating it from video is the calibration's job: mocap.calibration).
The TRC is Y-up; its axes in the calibration's world frame are the axis permutation whose
projection best matches the shipped OpenPose detections (found, not assumed). Compared: the
21 TRC markers against the same points (sites of the fitted body) on our solved skeleton.
Jitter: mean |second difference| of those points x rate^2 (m/s^2), ours and the TRC's.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from mocap import _core, paths
from mocap.calibration.rig import calibrate as rig_calibrate
from mocap.calibration.rig import compare as rig_compare
from mocap.eval import edge_detector
from mocap.io import calib_toml
from mocap.io.demo_data import TRIAL
from mocap.io.trc import Trc, read_trc
from mocap.model import frames, studio
from mocap.model.solver import Solver, solver_options
from mocap.net import wire
from mocap.sim import demo_motion

RATE = 60.0
# TRC marker -> OpenPose BODY_25B index, to find the TRC's axes.
BODY25B = {"Nose": 0, "LShoulder": 5, "RShoulder": 6, "LElbow": 7, "RElbow": 8, "LWrist": 9, "RWrist": 10,
           "LHip": 11, "RHip": 12, "LKnee": 13, "RKnee": 14, "LAnkle": 15, "RAnkle": 16}


def _rotations() -> list[np.ndarray]:
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product([1, -1], repeat=3):
            r = np.zeros((3, 3))
            r[range(3), perm] = signs
            if np.isclose(np.linalg.det(r), 1):
                out.append(r)
    return out


def trc_axes(rig: _core.Rig, trc: Trc, openpose: list[list[np.ndarray]]) -> np.ndarray:
    """The proper axis permutation R (calibration world = R @ TRC) whose projections of the
    TRC markers lie nearest OpenPose's keypoints (median pixel distance)."""
    idx = [trc.names.index(n) for n in BODY25B]
    best, best_err = None, np.inf
    for r in _rotations():
        errs = []
        for c, cam in enumerate(rig.cameras):
            for f in range(0, len(trc.markers), 10):
                px, ok = cam.project(trc.markers[f, idx] @ r.T)
                op = openpose[c][f][list(BODY25B.values())]
                use = ok & (op[:, 2] > 0)
                errs += list(np.linalg.norm(px[use] - op[use, :2], axis=1))
        err = np.median(errs) if errs else np.inf
        if err < best_err:
            best, best_err = r, err
    return best


def solve(trial: Path, keypoints: np.ndarray, openpose: list[list[np.ndarray]], settings: Sequence[str] = ()) -> dict:
    """keypoints (C, F, 33, 3) BlazePose pixels + confidence (0 where not detected); settings:
    solver options ("name=value", "term.field=value")."""
    rig = calib_toml.load(trial / "Calib_qualisys.toml")
    trc = read_trc(trial / TRIAL)
    body = demo_motion.body_model(trc.names, demo_motion.world_markers(trc))
    skeleton = body.skeleton
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / "blazepose33.json"), skeleton).scaled_to(skeleton)
    r = trc_axes(rig, trc, openpose)
    reference = trc.markers @ r.T  # (F, M, 3) calibration world
    solver = Solver(skeleton, rig, layout, [], options=solver_options(list(settings)))
    solved = []
    for frame in host_frames(rig, layout, keypoints):
        result = solver.solve(frame.time_ns * 1e-9, list(frame.cameras), frame.keypoints, [], np.zeros((0, 4)),
                              np.zeros((0, 3)))
        solved.append(studio.site_positions(skeleton, body.bones, body.offsets, result.theta))
    solved = np.array(solved)
    n = min(len(solved), len(reference))
    d = np.linalg.norm(solved[:n] - reference[:n], axis=-1)  # (F, M)
    return {"frames": n, "distance_cm": 100 * float(np.nanmean(d)), "distance_median_cm": 100 * float(np.nanmedian(d)),
            "per_marker_cm": {m: 100 * float(np.nanmean(d[:, i])) for i, m in enumerate(trc.names)},
            "per_marker_jitter_ms2": {m: jitter(solved[:n, i]) for i, m in enumerate(trc.names)},
            "jitter_ours_ms2": jitter(solved[:n]), "jitter_pose2sim_ms2": jitter(reference[:n]),
            "trc_axes": r.astype(int).tolist()}


def host_frames(rig: _core.Rig, layout: _core.KeypointLayout, keypoints: np.ndarray) -> list:
    """The synchronised frames (_core.SyncedFrame) of keypoints (C, F, K, 3), sent as the
    camera boxes send them (frame f captured and received at f / RATE, the tracked person,
    none where it was not found) through the host's input path; RuntimeError when it did not
    deliver every frame."""
    messages = []
    for f in range(keypoints.shape[1]):
        time_ns = int(round(f * 1e9 / RATE))
        for c, cam in enumerate(rig.cameras):
            persons = [keypoints[c, f]] if (keypoints[c, f, :, 2] > 0).any() else []
            msg = frames.camera_frame(cam, f, time_ns, layout.name, persons)
            messages.append(wire.arrived(time_ns, msg))
    times = [int(round(f * 1e9 / RATE)) for f in range(keypoints.shape[1])]
    return frames.synchronise_all(_core.InputPath(rig, [], layout), messages, times)


def jitter(x: np.ndarray, rate: float = RATE) -> float:
    """Mean |second difference| of points (F, ..., 3) x rate^2, m/s^2."""
    return float(np.nanmean(np.linalg.norm(x[2:] - 2 * x[1:-1] + x[:-2], axis=-1)) * rate**2)


def self_calibrated(trial: Path, keypoints: np.ndarray, height_m: float) -> dict:
    """The cameras' poses from keypoints (C, F, 33, 3) of the person alone (`mocap calibrate-rig`,
    the person height_m tall; the board's intrinsics), against the trial's board calibration."""
    board = calib_toml.load(trial / "Calib_qualisys.toml")
    people = [[k[None] if k[:, 2].any() else np.zeros((0,) + k.shape) for k in camera] for camera in keypoints]
    rig, report = rig_calibrate.calibrate(list(board.cameras), people, "blazepose33", RATE, height_m)
    found = rig_compare.compare(rig, board)
    return {"height_m": height_m, "up_from": report["up_from"],
            "reprojection_px_median": report["reprojection_px_median"],
            **{k: found[k] for k in ("position_cm_max", "orientation_deg_max", "scale_error_pct", "up_deg")}}


def detected(found: dict[int, list], frames: int) -> np.ndarray:
    """(C, F, 33, 3) the tracked person's keypoints per camera and frame, 0 where none."""
    keypoints = np.zeros((len(found), frames, 33, 3))
    for i, c in enumerate(edge_detector.CAMERAS):
        for f, person in enumerate(found[c]):
            if person is not None:
                keypoints[i, f] = person.keypoints
    return keypoints


def evaluate(trial: Path, settings: Sequence[str] = (), height_m: float | None = None) -> dict:
    """`mocap eval-edge`: the edge detector's PCK and speed (mocap.eval.edge_detector)
    and the video-only solve of its keypoints (with these solver settings) against Pose2Sim's TRC;
    with height_m, also the rig calibrated from those keypoints against the board's."""
    videos = edge_detector.load_trial(trial)
    model = edge_detector.BlazePose()
    found, speed = edge_detector.run(model, videos)
    naive, naive_speed = edge_detector.run(edge_detector.whole_image(model), videos, pack=False)
    keypoints = detected(found, len(videos[edge_detector.CAMERAS[0]]))
    openpose = [edge_detector.openpose_subjects(trial, c) for c in edge_detector.CAMERAS]
    result = {"detector_tracked": edge_detector.pck(trial, found) | speed,
              "detector_naive": edge_detector.pck(trial, naive) | naive_speed,
              "video_only_solve": solve(trial, keypoints, openpose, settings)}
    if height_m is not None:
        result["self_calibration"] = self_calibrated(trial, keypoints, height_m)
    return result
