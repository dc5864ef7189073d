"""Robust multi-view triangulation of keypoints, as Pose2Sim and anipose do it: every camera
pair is triangulated and scored by how many views reproject within `inlier_px`; the best
pair's inliers are triangulated together (DLT weighted by confidence).

The video-only baseline (mocap.eval.baselines) and the skeleton's first estimate
(mocap.calibration.skeleton) use it.
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from mocap import _core


@dataclasses.dataclass(frozen=True)
class TriangulationSettings:
    min_confidence: float = 0.3
    inlier_px: float = 20.0  # 1080p: ~3 sigma of the simulated detector's noise
    swap_ratio: float = 0.7  # mirror a camera when that cuts its reprojection error to this
    min_cutoff_hz: float = 1.0  # one-euro filter
    beta: float = 10.0  # one-euro speed coefficient, Hz per m/s (10: little lag at walking speed)
    d_cutoff_hz: float = 1.0


def _projections(rig: _core.Rig) -> np.ndarray:
    return np.array([np.hstack([c.rotation, c.translation[:, None]]) for c in rig.cameras])


def _dlt(p: np.ndarray, uv: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Points (..., 3) from projections p (C, 3, 4), normalised coords uv (..., C, 2), weights (..., C)."""
    rows = np.concatenate([w[..., None] * (uv[..., :1] * p[:, 2] - p[:, 0]),
                           w[..., None] * (uv[..., 1:] * p[:, 2] - p[:, 1])], axis=-2)
    x = np.linalg.svd(rows)[2][..., -1, :]
    return x[..., :3] / np.where(np.abs(x[..., 3:]) > 1e-12, x[..., 3:], 1e-12)


def reprojection_error(rig: _core.Rig, points: np.ndarray, pixels: np.ndarray) -> np.ndarray:
    """(C, N) pixel errors of points (N, 3) against pixels (C, N, 2); inf where not projectable."""
    err = np.full(pixels.shape[:2], np.inf)
    for c, cam in enumerate(rig.cameras):
        px, ok = cam.project(np.nan_to_num(points))
        err[c, ok] = np.linalg.norm(px[ok] - pixels[c, ok], axis=1)
    return err


def triangulate(rig: _core.Rig, det: np.ndarray, s: TriangulationSettings) -> tuple[np.ndarray, np.ndarray]:
    """(K, 3) points and (K,) validity from detections (C, K, 3) [x, y, confidence]."""
    n_cams, k = det.shape[:2]
    p = _projections(rig)
    uv = np.stack([cam.undistort(det[c, :, :2]) for c, cam in enumerate(rig.cameras)])  # (C, K, 2)
    seen = det[..., 2] > s.min_confidence
    pairs = list(itertools.combinations(range(n_cams), 2))
    if not pairs:
        return np.zeros((k, 3)), np.zeros(k, bool)
    w = np.zeros((len(pairs), k, n_cams))
    for i, (a, b) in enumerate(pairs):
        w[i, :, a], w[i, :, b] = seen[a], seen[b]
    both = w.sum(axis=-1) == 2  # (pairs, K)
    cand = _dlt(p, np.broadcast_to(np.swapaxes(uv, 0, 1), (len(pairs), k, n_cams, 2)), w)
    err = reprojection_error(rig, cand.reshape(-1, 3), np.tile(det[..., :2], (1, len(pairs), 1)))
    err = err.reshape(n_cams, len(pairs), k).transpose(1, 2, 0)  # (pairs, K, C)
    inlier = (err < s.inlier_px) & seen.T[None]
    score = np.where(both, inlier.sum(-1) - 1e-3 * np.where(inlier, err, 0).sum(-1) / s.inlier_px, -1)
    best = score.argmax(axis=0)  # (K,)
    chosen = inlier[best, np.arange(k)]  # (K, C)
    valid = chosen.sum(-1) >= 2
    points = _dlt(p, np.swapaxes(uv, 0, 1), chosen * det[..., 2].T)
    return points, valid
