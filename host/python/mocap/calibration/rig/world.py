"""The world a self-calibrated rig is put in: metres from a stated body height, Z up from the
person, the origin on the floor under them, X the way they face on average.

Scale: the person's median shin, thigh and trunk (mid-hip to mid-shoulder) lengths over the
take and, when the layout has a head-top keypoint, the mid-shoulder to head-top length: standing,
these four stack into the height but for the ankle's height above the floor (3.9% of it). Without
a head top, the three against their shares of body height (0.246, 0.245 and 0.288): a population's
proportions, a few percent off a given person's. Shares from Winter's anthropometric table
("Biomechanics and Motor Control of Human Movement", 4th ed., fig. 4.1).
Up: the normal of the floor the still feet stand on when they cover an area; otherwise the
person's mean standing axis (the foot they stand on to their shoulders), which leans with
their posture, levelled along the feet's path when they walk a line.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap.calibration.rig.bundle import Cameras
from mocap.calibration.skeleton import ALIASES
from mocap.errors import InputError

SHARE_OF_HEIGHT = {"shin": 0.246, "thigh": 0.245, "trunk": 0.288}
SEGMENTS = {"shin": [("left_knee", "left_ankle"), ("right_knee", "right_ankle")],
            "thigh": [("left_hip", "left_knee"), ("right_hip", "right_knee")],
            "trunk": [(("left_hip", "right_hip"), ("left_shoulder", "right_shoulder"))]}
HEAD = [(("left_shoulder", "right_shoulder"), "HeadTop")]  # OpenPose BODY_25B's top of the head
MIN_MEASURES = 10  # frames (and sides) a segment must be measured on to count
ANKLE_HEIGHT = 0.039  # of the body height, when no heel or toe keypoint marks the floor
STILL_M_S = 0.15  # a foot keypoint slower than this stands on the floor
STILL_SPAN_S = 0.2
ON_FLOOR_M = 0.05  # a foot keypoint this much above the other foot's is in the air
FLOOR_SPREAD_M = 0.3  # the still feet must cover this much (+-2 sd) in both floor directions
FOOT = ("left_ankle", "right_ankle", "left_heel", "right_heel", "left_foot_index", "right_foot_index")


@dataclasses.dataclass
class World:
    scale: float  # metres per unit of the adjusted rig
    up_from: str  # what set the vertical (up_axis)
    person_height_units: float  # the height the segment lengths imply, before scaling


def named(points: np.ndarray, names: list[str]) -> dict[str, np.ndarray]:
    """Layout keypoints (F, K, 3) by our names (left_hip, left_heel, ...)."""
    return {ALIASES.get(name, name): points[:, k] for k, name in enumerate(names)}


def _mid(kp: dict, a: str, b: str) -> np.ndarray:
    return (kp[a] + kp[b]) / 2


def _segment(kp: dict, pairs: list[tuple]) -> float:
    """Median length over frames and sides of a segment (ends: a keypoint or a pair's middle)."""
    def at(end):
        return _mid(kp, *end) if isinstance(end, tuple) else kp[end]
    lengths = np.concatenate([np.linalg.norm(at(a) - at(b), axis=1) for a, b in pairs])
    lengths = lengths[np.isfinite(lengths)]
    return float(np.median(lengths)) if len(lengths) >= MIN_MEASURES else np.nan


def body_height(kp: dict) -> float:
    """The height (in the points' units) the median segment lengths imply: the shin, thigh,
    trunk and head stacked when all four were measured, else the shares of those that were."""
    lengths = {name: _segment(kp, pairs) for name, pairs in SEGMENTS.items()}
    head = _segment(kp, HEAD) if "HeadTop" in kp else np.nan
    if np.isfinite([head, *lengths.values()]).all():
        return (head + sum(lengths.values())) / (1 - ANKLE_HEIGHT)
    seen = [name for name, v in lengths.items() if np.isfinite(v)]
    if not seen:
        raise InputError("no shin, thigh or trunk of the person was seen by two cameras on "
                         f"{MIN_MEASURES} frames: nothing sets the scale")
    return sum(lengths[n] for n in seen) / sum(SHARE_OF_HEIGHT[n] for n in seen)


def _upper(kp: dict) -> np.ndarray:
    """(F, 3) the middle of the shoulders, or the nose where they are not seen."""
    shoulders = _mid(kp, "left_shoulder", "right_shoulder")
    nose = kp.get("nose", kp.get("Nose"))
    if nose is not None:
        shoulders = np.where(np.isfinite(shoulders), shoulders, nose)
    return shoulders


def _feet_on_floor(kp: dict, rate: float, axis: np.ndarray) -> list[np.ndarray]:
    """Per foot keypoint, its positions on the frames it is on the floor: slower than
    STILL_M_S (measured over STILL_SPAN_S: a frame-to-frame difference is mostly the
    detections' noise) and not above the other foot's (a foot held still in the air)."""
    k = max(1, round(STILL_SPAN_S * rate / 2))
    found = []
    soles = [n for n in FOOT[2:] if n in kp]  # on the floor; the ankles only when there are none
    for name in soles or FOOT[:2]:
        p, other = kp[name], kp[name.replace("left", "@").replace("right", "left").replace("@", "right")]
        if len(p) > 2 * k:
            speed = np.full(len(p), np.inf)
            speed[k:-k] = np.linalg.norm(p[2 * k:] - p[:-2 * k], axis=1) * rate / (2 * k)
            with np.errstate(invalid="ignore"):
                low = ~((p - other) @ axis > ON_FLOOR_M)  # the other foot unseen: kept
                found.append(p[(speed < STILL_M_S) & low & np.isfinite(p).all(axis=1)])
    return found


def standing_axis(kp: dict) -> np.ndarray:
    """The mean direction from the foot the person stands on (the lower ankle) to the middle of
    their shoulders: their weight is over that foot whether they stand on one or two."""
    shoulders = _upper(kp)
    axis = np.nanmean(shoulders - _mid(kp, "left_ankle", "right_ankle"), axis=0)
    for _ in range(3):  # which ankle is lower depends on the axis: a few rounds settle it
        axis /= np.linalg.norm(axis)
        lower = np.where(((kp["left_ankle"] - kp["right_ankle"]) @ axis < 0)[:, None], kp["left_ankle"],
                         kp["right_ankle"])
        d = shoulders - lower
        d = d[np.isfinite(d).all(axis=1)]
        axis = (d / np.linalg.norm(d, axis=1, keepdims=True)).mean(axis=0)
    return axis / np.linalg.norm(axis)


def up_axis(kp: dict, rate: float) -> tuple[np.ndarray, str]:
    """Unit up vector (metric points) and where it came from: the floor's normal when the
    still feet cover an area; the standing axis levelled along their path when they cover a
    line (a straight walk: the path is horizontal); the standing axis alone otherwise."""
    axis = standing_axis(kp)
    # Each keypoint about its own mean: a heel keypoint sits higher than a toe's; only where
    # each moved across the floor counts.
    feet = [p - p.mean(axis=0) for p in _feet_on_floor(kp, rate, axis) if len(p)]
    feet = np.concatenate(feet) if feet else np.zeros((0, 3))
    if len(feet) < 20:
        return axis, "standing axis"
    _, s, vt = np.linalg.svd(feet, full_matrices=False)
    spread = 4 * s / np.sqrt(len(feet))  # +-2 standard deviations
    if spread[1] >= FLOOR_SPREAD_M:
        return vt[2] * np.sign(vt[2] @ axis), "floor"
    if spread[0] >= FLOOR_SPREAD_M:
        levelled = axis - (axis @ vt[0]) * vt[0]
        return levelled / np.linalg.norm(levelled), "standing axis levelled along the feet's path"
    return axis, "standing axis"


def _mean_seen(values: list[np.ndarray], what: str) -> np.ndarray:
    """Mean over frames of the first of `values` (F, 3) measured on MIN_MEASURES frames."""
    for v in values:
        v = v[np.isfinite(v).all(axis=1)]
        if len(v) >= MIN_MEASURES:
            return v.mean(axis=0)
    raise InputError(f"the person's {what} were not seen by two cameras on {MIN_MEASURES} frames")


def frame(kp: dict, up: np.ndarray, height_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(A, b): p_world = A p + b for metric points p: Z up, X the mean facing, origin on the
    floor under the mean mid-hip."""
    left = _mean_seen([kp[f"left_{j}"] - kp[f"right_{j}"] for j in ("shoulder", "hip")], "shoulders or hips")
    forward = np.cross(left, up)
    forward /= np.linalg.norm(forward)
    a = np.stack([forward, np.cross(up, forward), up])
    feet = [kp[n] @ up for n in FOOT[2:] if n in kp and np.isfinite(kp[n]).all(axis=1).sum() >= MIN_MEASURES]
    if feet:
        floor = np.nanpercentile(np.concatenate(feet), 2)
    else:
        floor = np.nanpercentile(np.r_[kp["left_ankle"] @ up, kp["right_ankle"] @ up], 2) - ANKLE_HEIGHT * height_m
    centre = _mean_seen([_mid(kp, f"left_{j}", f"right_{j}") for j in ("hip", "ankle")], "hips or ankles")
    origin = centre - (centre @ up - floor) * up
    return a, -a @ origin


def place(cams: Cameras, points: np.ndarray, frames: np.ndarray, names: list[str], n_frames: int,
          rate: float, height_m: float) -> tuple[Cameras, np.ndarray, World]:
    """The cameras and points in metres and in the person's world. frames: (P, 2) each
    point's (frame, keypoint)."""
    grid = np.full((n_frames, len(names), 3), np.nan)
    grid[frames[:, 0], frames[:, 1]] = points
    units = body_height(named(grid, names))
    scale = height_m / units
    kp = named(grid * scale, names)
    up, source = up_axis(kp, rate)
    a, b = frame(kp, up, height_m)
    rotation = cams.rotation @ a.T
    translation = scale * cams.translation - np.einsum("cij,j->ci", rotation, b)
    return Cameras(rotation, translation), (scale * points) @ a.T + b, World(scale, source, units)
