"""Self-occlusion: the body as capsules around its bone segments.

A keypoint is hidden from a camera when the ray from the camera centre to it passes
through a capsule of another body part (its own bone's and its neighbours' capsules are
skipped: the keypoint lies inside them), or of another person's body when several share the
stage (mocap.sim.people).
"""

from __future__ import annotations

import numpy as np

# Capsule radius (m) of the segment from a bone's origin to its child's origin, by the
# bone's name prefix. The head's segment runs 0.2 m up from its origin.
RADIUS = {"pelvis": 0.13, "spine": 0.14, "neck": 0.05, "head": 0.09, "clavicle": 0.05,
          "upper_arm": 0.05, "forearm": 0.04, "hand": 0.04, "thigh": 0.08, "shin": 0.055,
          "foot": 0.045, "toes": 0.03}


def _radius(name: str) -> float:
    return next(r for prefix, r in RADIUS.items() if name.startswith(prefix))


def capsules(names: list[str], parents: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(segment start bone, segment end bone or -1 for "head top", radius) per capsule."""
    pairs = [(p, b, _radius(names[p])) for b, p in enumerate(parents) if p >= 0]
    pairs.append((names.index("head"), -1, _radius("head")))
    start, end, radius = zip(*pairs)
    return np.array(start), np.array(end), np.array(radius)


def _segment_distance(p0, p1, q0, q1) -> np.ndarray:
    """Distances between segments [p0, p1] and [q0, q1], broadcast over leading axes."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e = (d1 * d1).sum(-1), (d2 * d2).sum(-1)
    b, c, f = (d1 * d2).sum(-1), (d1 * r).sum(-1), (d2 * r).sum(-1)
    denom = np.maximum(a * e - b * b, 1e-12)
    s = np.clip((b * f - c * e) / denom, 0.0, 1.0)
    t = np.clip((b * s + f) / np.maximum(e, 1e-12), 0.0, 1.0)
    s = np.clip((b * t - c) / np.maximum(a, 1e-12), 0.0, 1.0)
    return np.linalg.norm(p0 + d1 * s[..., None] - (q0 + d2 * t[..., None]), axis=-1)


def segments(rot: np.ndarray, pos: np.ndarray, caps) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The capsules of a body in a pose (bone rotations and origins from forward kinematics):
    (start points, end points, radii)."""
    start, end, radius = caps
    a = pos[start]
    b = np.where((end >= 0)[:, None], pos[np.maximum(end, 0)], pos[start] + rot[start] @ np.array([0, 0, 0.2]))
    return a, b, radius


def hidden(centres: np.ndarray, points: np.ndarray, point_bones: np.ndarray, rot: np.ndarray,
           pos: np.ndarray, caps, parents: list[int], others: tuple | None = None) -> np.ndarray:
    """(cameras, K) True where keypoint k is hidden from camera c; others: the segments() of
    the other people on the stage, concatenated (each of their capsules can hide it)."""
    start, end, radius = caps
    a, b, _ = segments(rot, pos, caps)
    # Capsules touching the keypoint's bone (as start or end) or its parent are its own.
    own = np.zeros((len(points), len(start)), dtype=bool)
    for k, bone in enumerate(point_bones):
        near = {bone, parents[bone]}
        own[k] = np.isin(start, list(near)) | np.isin(end, list(near))
    cam = centres[:, None, None, :]
    tip = points[None, :, None, :]
    ray_end = cam + (tip - cam) * 0.98  # stop just short of the keypoint itself
    dist = _segment_distance(cam, ray_end, a[None, None], b[None, None])
    out = ((dist < radius[None, None]) & ~own[None]).any(axis=-1)
    if others is not None and len(others[0]):
        oa, ob, oradius = others
        out |= (_segment_distance(cam, ray_end, oa[None, None], ob[None, None]) < oradius[None, None]).any(axis=-1)
    return out
