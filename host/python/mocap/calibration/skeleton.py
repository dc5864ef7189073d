"""The subject's skeleton from the first seconds of multi-view keypoints.

Keypoints are triangulated robustly per frame (mocap.model.triangulation: best camera
pair's inliers). For each length the layout defines by two keypoints (hip to knee, knee to
ankle, shoulder to elbow, elbow to wrist, hip and shoulder width, hips' to shoulders' centre,
ankle to foot tip), the median over frames of the triangulated distance is compared with the
same distance on the default skeleton at rest (the layout's sites included), left and right
pooled; the ratio scales the bones of that group. A distance is used only where both
keypoints were triangulated from inliers; a group with too few frames keeps the overall
scale (the median of the other ratios).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap import _core, paths
from mocap.model import studio, triangulation

# Group -> bones whose offsets (from their parent) it scales.
GROUPS = {"hip_width": ["thigh_l", "thigh_r"], "thigh": ["shin_l", "shin_r"], "shin": ["foot_l", "foot_r"],
          "foot": ["toes_l", "toes_r"], "trunk": ["spine_lower", "spine_upper", "neck", "head"],
          "shoulder_width": ["clavicle_l", "clavicle_r", "upper_arm_l", "upper_arm_r"],
          "upper_arm": ["forearm_l", "forearm_r"], "forearm": ["hand_l", "hand_r"]}
# Group -> keypoint pairs measuring it, by layout keypoint names ("L/R" sides; centres as tuples).
PAIRS = {
    "thigh": [("left_hip", "left_knee"), ("right_hip", "right_knee")],
    "shin": [("left_knee", "left_ankle"), ("right_knee", "right_ankle")],
    "upper_arm": [("left_shoulder", "left_elbow"), ("right_shoulder", "right_elbow")],
    "forearm": [("left_elbow", "left_wrist"), ("right_elbow", "right_wrist")],
    "hip_width": [("left_hip", "right_hip")],
    "shoulder_width": [("left_shoulder", "right_shoulder")],
    "trunk": [(("left_hip", "right_hip"), ("left_shoulder", "right_shoulder"))],
    "foot": [("left_ankle", "left_foot_index"), ("right_ankle", "right_foot_index")],
}
# Other layouts' names for the same keypoints.
ALIASES = {"LHip": "left_hip", "RHip": "right_hip", "LKnee": "left_knee", "RKnee": "right_knee",
           "LAnkle": "left_ankle", "RAnkle": "right_ankle", "LShoulder": "left_shoulder",
           "RShoulder": "right_shoulder", "LElbow": "left_elbow", "RElbow": "right_elbow", "LWrist": "left_wrist",
           "RWrist": "right_wrist", "LBigToe": "left_foot_index", "RBigToe": "right_foot_index",
           "LHeel": "left_heel", "RHeel": "right_heel"}
MIN_FRAMES = 10


@dataclasses.dataclass
class SkeletonEstimate:
    skeleton: _core.Skeleton
    scales: dict[str, float]  # per group: estimated / default
    lengths_m: dict[str, float]  # per group: the median triangulated distance
    frames: dict[str, int]  # per group: frames that measured it


def scaled(base: _core.Skeleton, scales: dict[str, float]) -> _core.Skeleton:
    offsets = np.array(base.offsets)
    names = base.bone_names
    for group, bones in GROUPS.items():
        for b in bones:
            offsets[names.index(b)] *= scales.get(group, 1.0)
    return _core.Skeleton.from_bones(names, list(base.parents), offsets)


def triangulated(rig: _core.Rig, detections: np.ndarray) -> np.ndarray:
    """(F, K, 3) points, NaN where not triangulated from inliers, of detections (F, C, K, 3)."""
    out = np.full(detections.shape[:1] + detections.shape[2:3] + (3,), np.nan)
    settings = triangulation.TriangulationSettings()
    for f, det in enumerate(detections):
        points, valid = triangulation.triangulate(rig, det, settings)
        out[f, valid] = points[valid]
    return out


def _point(points: np.ndarray, index: dict[str, int], key) -> np.ndarray | None:
    if isinstance(key, tuple):
        parts = [_point(points, index, k) for k in key]
        return None if any(p is None for p in parts) else np.mean(parts, axis=0)
    return points[..., index[key], :] if key in index else None


def _distances(points: np.ndarray, names: list[str], pairs) -> np.ndarray:
    index = {ALIASES.get(n, n): i for i, n in enumerate(names)}
    out = []
    for a, b in pairs:
        pa, pb = _point(points, index, a), _point(points, index, b)
        if pa is not None and pb is not None:
            out.append(np.linalg.norm(pa - pb, axis=-1))
    return np.concatenate([np.atleast_1d(d) for d in out]) if out else np.array([])


def estimate(rig: _core.Rig, detections: np.ndarray, layout_name: str,
             base: _core.Skeleton | None = None) -> SkeletonEstimate:
    """The skeleton of the subject seen in detections (F, C, K, 3) of the layout."""
    base = base or _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / f"{layout_name}.json"), base).scaled_to(base)
    rest = studio.site_positions(base, layout.bones, layout.offsets, np.zeros(base.pose_dim))
    points = triangulated(rig, detections)
    scales, lengths, frames = {}, {}, {}
    for group, pairs in PAIRS.items():
        measured = _distances(points, layout.names, pairs)
        measured = measured[np.isfinite(measured)]
        reference = _distances(rest, layout.names, pairs)
        frames[group] = len(measured)
        if len(measured) >= MIN_FRAMES and len(reference) and reference.mean() > 1e-6:
            lengths[group] = float(np.median(measured))
            scales[group] = lengths[group] / float(reference.mean())
    overall = float(np.median(list(scales.values()))) if scales else 1.0
    for group in GROUPS:
        scales.setdefault(group, overall)
    return SkeletonEstimate(scaled(base, scales), scales, lengths, frames)
