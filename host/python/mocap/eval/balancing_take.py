"""Pose2Sim's Balancing trial (mocap.io.demo_data.fetch_trial) as a take folder: its four
cameras' OpenPose BODY_25B detections and Qualisys calibration, nothing else (no IMUs) —
and the comparison of a solve of it with Pose2Sim's own triangulated TRC."""

from __future__ import annotations

import csv
import shutil
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from mocap.calibration.rig import calibrate as rig_calibrate
from mocap.calibration.rig import compare as rig_compare
from mocap.calibration.rig import views as rig_views
from mocap.eval import real_trial
from mocap.io import calib_toml, retarget, take_folder
from mocap.io.take_folder import KEYPOINTS
from mocap.io.demo_data import TRIAL
from mocap.io.joints_csv import read_positions_csv, write_positions_csv
from mocap.io.trc import POSE2SIM_MARKERS, read_trc
from mocap.takes import solve as take_solve

MARKERS = POSE2SIM_MARKERS  # joints.csv columns -> Pose2Sim's TRC markers


BOARD = "Calib_qualisys.toml"  # the trial's own calibration (a Qualisys wand and frame)
SELF = "Calib_self.toml"  # one `mocap calibrate-rig` made from the take's detections


def write(trial: Path, folder: Path) -> Path:
    """A take folder of the trial's files (copied in: a take reads nothing outside its folder)."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(trial / BOARD, folder / BOARD)
    for c in range(1, 5):
        shutil.copytree(trial / "pose" / f"cam{c}_json", folder / "pose" / f"cam{c}_json", dirs_exist_ok=True)
    _take_toml(folder, BOARD)
    return folder


def _take_toml(folder: Path, calibration: str) -> None:
    poses = ", ".join(f'"pose/cam{c}_json"' for c in range(1, 5))
    (folder / "take.toml").write_text(
        "[take]\nframe_rate = 60\nn_frames = 100\nworld_up_axis = \"Z\"\nunits = \"m\"\n\n"
        f"[video]\ncalibration = \"{calibration}\"\n"
        "camera_names = [\"cam_01\", \"cam_02\", \"cam_03\", \"cam_04\"]\n"
        f"pose_dirs = [{poses}]\nkeypoint_layout = \"BODY_25B\"\n")


def compare(trial: Path, joints_csv: Path, rate: float = 60.0) -> dict:
    """Distance of the solved joint centres to Pose2Sim's markers (calibration world: the
    TRC's Y-up axes rotated as retarget.P), and both jitters (mean |second difference| x rate^2).
    Of the distance, per joint the part no temporal model changes, |mean offset| (bias), and
    the mean distance after a zero-phase Gaussian (2 frames) of our joints: what smoothing
    alone, without the causal lag, would reach."""
    trc = read_trc(trial / TRIAL)
    reference = trc.markers @ retarget.P.T
    rows = list(csv.reader(open(joints_csv)))
    header, values = rows[0], np.array([[float(v) for v in r] for r in rows[1:]])
    ours = np.stack([values[:, [header.index(f"{j}_{a}") for a in "xyz"]] for j in MARKERS], axis=1)
    theirs = reference[:, [trc.names.index(m) for m in MARKERS.values()]]
    n = min(len(ours), len(theirs))
    d = np.linalg.norm(ours[:n] - theirs[:n], axis=-1)
    bias = np.linalg.norm(np.nanmean(ours[:n] - theirs[:n], axis=0), axis=-1)
    smoothed = np.linalg.norm(_zero_phase(ours[:n], 2.0) - theirs[:n], axis=-1)
    return {"frames": n, "distance_cm": 100 * float(np.nanmean(d)),
            "per_joint_cm": {j: 100 * float(np.nanmean(d[:, i])) for i, j in enumerate(MARKERS)},
            "per_joint_bias_cm": {j: 100 * float(bias[i]) for i, j in enumerate(MARKERS)},
            "distance_zero_phase_smoothed_cm": 100 * float(np.nanmean(smoothed)),
            "jitter_ours_ms2": real_trial.jitter(ours[:n], rate),
            "jitter_pose2sim_ms2": real_trial.jitter(theirs[:n], rate)}


def _zero_phase(x: np.ndarray, sigma: float) -> np.ndarray:
    """x (F, ...) smoothed along its first axis by a Gaussian of `sigma` frames (ends held)."""
    k = np.arange(-int(4 * sigma), int(4 * sigma) + 1)
    w = np.exp(-0.5 * (k / sigma) ** 2)
    padded = np.concatenate([np.repeat(x[:1], len(k) // 2, 0), x, np.repeat(x[-1:], len(k) // 2, 0)])
    return sum(wi * padded[i: i + len(x)] for i, wi in enumerate(w / w.sum()))

def evaluate(trial: Path, out: Path, settings: Sequence[str] = ()) -> dict:
    """`mocap eval-edge --take-solve OUT`: the trial written as a take folder (OUT/take), solved
    by `mocap solve --take` (OUT/solved; `settings`: solver options of the solve after the
    calibration) and compared with Pose2Sim's TRC."""
    report = take_solve.solve_take(write(trial, out / "take"), out / "solved", settings)
    return {"statuses": report["solve"]["statuses"], "settings": list(settings),
            **compare(trial, out / "solved" / "joints.csv", report["frame_rate"])}


def evaluate_self_calibrated(trial: Path, out: Path, height_m: float, settings: Sequence[str] = ()) -> dict:
    """`mocap eval-edge --take-solve OUT --self-calibrate H`: the take with its board calibration
    replaced by one made from its own detections (mocap.calibration.rig, the person H metres tall),
    solved, and its joints brought into the board's world before the comparison with Pose2Sim's
    TRC (whose markers were triangulated with the board's rig): by the similarity between the
    take's detections triangulated through each rig (the figures at the top level), and by the
    one that takes the self-calibrated camera centres onto the board's (`aligned_by_the_cameras`);
    `rig`: the rigs' comparison."""
    folder = write(trial, out / "take")
    take = take_folder.read_take(folder)
    rig, _ = rig_calibrate.calibrate(list(take.rig.cameras), take.people, take.layout, take.frame_rate, height_m)
    (folder / SELF).write_text(calib_toml.dumps(rig))
    _take_toml(folder, SELF)
    report = take_solve.solve_take(folder, out / "solved", settings)
    keypoints = KEYPOINTS[take.layout]
    detections = np.stack([rig_views.person_in_view(p, keypoints) for p in take.people], axis=1)  # (F, C, K, 3)
    by_the_scene, points, residual = rig_compare.by_the_scene(rig, take.rig, detections)
    compared = {}
    for name, (s, r, t) in (("scene", by_the_scene),
                            ("cameras", rig_compare.similarity(rig_compare.centres(rig), rig_compare.centres(take.rig)))):
        aligned = out / "solved" / f"joints_in_the_boards_world_by_the_{name}.csv"
        _moved_joints(out / "solved" / "joints.csv", aligned, s * r, t)
        compared[name] = compare(trial, aligned, report["frame_rate"])
    return {"statuses": report["solve"]["statuses"], "settings": list(settings), "height_m": height_m,
            "rig": rig_compare.compare(rig, take.rig), **compared["scene"],
            "scene_alignment": {"points": points, "median_distance_cm": 100 * residual},
            "aligned_by_the_cameras": {k: compared["cameras"][k] for k in ("distance_cm", "per_joint_cm")}}


def _moved_joints(source: Path, target: Path, linear: np.ndarray, shift: np.ndarray) -> None:
    """joints.csv with every position p replaced by linear p + shift."""
    names, positions, times = read_positions_csv(source)
    write_positions_csv(target, names, positions @ linear.T + shift, times)
