"""How far a self-calibrated rig is from a reference one (a board's): the similarity that best
takes its camera centres onto the reference's (Umeyama), then per camera the centre's distance
and the orientation's angle; the scale; the angle between the two worlds' up axes. And the
similarity between the two worlds where the person is: the same detections triangulated
through each rig."""

from __future__ import annotations

import numpy as np

from mocap import _core, rotations
from mocap.model import triangulation


def centres(rig: _core.Rig) -> np.ndarray:
    return np.array([-np.asarray(c.rotation).T @ np.asarray(c.translation) for c in rig.cameras])


def similarity(a: np.ndarray, b: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """(s, R, t) minimising |s R a_i + t - b_i| over the rows."""
    ma, mb = a.mean(axis=0), b.mean(axis=0)
    u, d, vt = np.linalg.svd((b - mb).T @ (a - ma))
    flip = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
    r = u @ flip @ vt
    s = float((d * np.diag(flip)).sum() / ((a - ma) ** 2).sum())
    return s, r, mb - s * r @ ma


def compare(estimated: _core.Rig, reference: _core.Rig) -> dict:
    """The estimate against the reference, camera by camera (same order and names)."""
    a, b = centres(estimated), centres(reference)
    s, r, t = similarity(a, b)
    cm = 100 * np.linalg.norm(s * a @ r.T + t - b, axis=1)
    deg = [float(np.degrees(rotations.angle_between(np.asarray(e.rotation) @ r.T, np.asarray(f.rotation))))
           for e, f in zip(estimated.cameras, reference.cameras)]
    return {"cameras": {c.name: {"position_cm": float(p), "orientation_deg": d}
                        for c, p, d in zip(reference.cameras, cm, deg)},
            "position_cm_max": float(cm.max()), "orientation_deg_max": max(deg),
            "scale_error_pct": 100 * (1 / s - 1),  # + : the estimate is larger than the reference
            "up_deg": float(np.degrees(np.arccos(np.clip(r[:, 2] @ [0.0, 0.0, 1.0], -1, 1))))}


def by_the_scene(estimated: _core.Rig, reference: _core.Rig,
                 detections: np.ndarray) -> tuple[tuple[float, np.ndarray, np.ndarray], int, float]:
    """(s, R, t) taking the estimate's world onto the reference's: the similarity between the
    points of detections (F, C, K, 3), the cameras in both rigs' order, triangulated through
    each rig (every keypoint both triangulate); how many points, and their median distance
    after it (m). Four camera centres fix it loosely; the thousands of points of a take fix it
    where the person moves."""
    settings = triangulation.TriangulationSettings()
    ours, theirs = [], []
    for frame in detections:
        a, seen_a = triangulation.triangulate(estimated, frame, settings)
        b, seen_b = triangulation.triangulate(reference, frame, settings)
        ours.append(a[seen_a & seen_b])
        theirs.append(b[seen_a & seen_b])
    a, b = np.concatenate(ours), np.concatenate(theirs)
    s, r, t = similarity(a, b)
    return (s, r, t), len(a), float(np.median(np.linalg.norm(s * a @ r.T + t - b, axis=1)))
