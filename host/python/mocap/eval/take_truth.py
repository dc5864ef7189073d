"""`mocap eval --take DIR`: a simulated take folder (`mocap simulate --take-out`, any motion and
keypoint layout) solved as a user's take is (`mocap solve --take`: the calibration estimated
from the take, nothing of the truth) and scored against the truth written beside it.

Orientation errors are given plain and with each bone's constant offset removed
(metrics.offset_removed_errors_deg: the estimated skeleton's rest frames need not be the
clip's), per bone and over the bones that carry a sensor; `upside_down_frames` counts the
frames a bone is more than a quarter turn off, which no constant offset explains away.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from mocap import _core
from mocap.errors import InputError
from mocap.eval import metrics
from mocap.takes import solve as take_solve


def _truth(folder: Path) -> tuple[_core.Skeleton, np.ndarray, dict]:
    path = folder / "truth.json"
    if not path.exists():
        raise InputError(f"{path} is absent: only a take written by `mocap simulate` carries its truth")
    truth = json.loads(path.read_text())
    return (_core.Skeleton.load(str(folder / truth["skeleton"])), np.load(folder / truth["thetas"]), truth)


def score(folder: Path, out: Path) -> dict:
    """Solves the take into `out` and scores it against its truth."""
    _truth(folder)  # a take without its truth is refused before the solve
    return score_solved(folder, take_solve.solve(folder, out))


def score_solved(folder: Path, solved: take_solve.SolvedTake) -> dict:
    """A solve of the take folder scored against the truth written beside it."""
    skeleton, truth_thetas, truth = _truth(folder)
    fk = [solved.skeleton.forward_kinematics(th) for th in solved.thetas]
    r_s, p_s = np.array([r for r, _ in fk]), np.array([p for _, p in fk])
    e = metrics.transform_errors(skeleton, truth_thetas, p_s, r_s, 1.0 / truth["frame_rate"])
    sensor_bones = sorted({s["bone"] for s in truth["sensors"].values()})
    per_bone = e["per_joint"]
    report = solved.report
    return {"take": str(folder), "frames": len(solved.thetas),
            **{k: e[k] for k in ("ori_error_deg", "ori_error_offset_removed_deg", "joint_centres_pos_cm",
                                 "joint_centres_vel_cms", "upside_down_frames")},
            "sensor_bones_offset_removed_deg": float(np.mean(
                [per_bone[b]["ori_offset_removed_deg"] for b in sensor_bones])),
            "worst_sensor_bone": max(sensor_bones, key=lambda b: per_bone[b]["ori_offset_removed_deg"]),
            "per_bone": {b: {k: round(v, 2) for k, v in d.items()} for b, d in per_bone.items()},
            "imus_not_used_because": report["imus_not_used_because"],
            "distrusted": report["solve"]["distrusted"]}
