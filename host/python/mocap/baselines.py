"""What users would pick instead of the fused solver, scored by the same evaluation.

Video only, real time (as Pose2Sim and anipose do it, made causal):
1. robust triangulation per keypoint: every camera pair is triangulated and scored by how
   many views reproject within `inlier_px`; the best pair's inliers are triangulated
   together (DLT weighted by confidence);
2. left/right swap fix: a camera whose detections reproject better mirrored is mirrored;
3. causal smoothing: a one-euro filter per coordinate (Casiez et al. 2012);
4. bone-length-constrained fit: the skeleton (true bone lengths) fitted to the smoothed
   points (FitToPoints, warm-started from the previous frame).
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from mocap import _core, studio
from mocap.sim import detector


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


def _reprojection_error(rig: _core.Rig, points: np.ndarray, pixels: np.ndarray) -> np.ndarray:
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
    err = _reprojection_error(rig, cand.reshape(-1, 3), np.tile(det[..., :2], (1, len(pairs), 1)))
    err = err.reshape(n_cams, len(pairs), k).transpose(1, 2, 0)  # (pairs, K, C)
    inlier = (err < s.inlier_px) & seen.T[None]
    score = np.where(both, inlier.sum(-1) - 1e-3 * np.where(inlier, err, 0).sum(-1) / s.inlier_px, -1)
    best = score.argmax(axis=0)  # (K,)
    chosen = inlier[best, np.arange(k)]  # (K, C)
    valid = chosen.sum(-1) >= 2
    points = _dlt(p, np.swapaxes(uv, 0, 1), chosen * det[..., 2].T)
    return points, valid


def fix_swaps(rig: _core.Rig, det: np.ndarray, points: np.ndarray, valid: np.ndarray, twins: np.ndarray,
              s: TriangulationSettings) -> np.ndarray:
    """Detections with each camera mirrored where the mirror reprojects markedly better."""
    out = det.copy()
    err = _reprojection_error(rig, points, det[..., :2])
    err_m = _reprojection_error(rig, points, det[:, twins, :2])
    for c in range(len(det)):
        use = valid & (det[c, :, 2] > s.min_confidence) & (det[c, twins, 2] > s.min_confidence)
        e, em = np.minimum(err[c, use], 10 * s.inlier_px).sum(), np.minimum(err_m[c, use], 10 * s.inlier_px).sum()
        if use.any() and em < s.swap_ratio * e:
            out[c] = det[c, twins]
    return out


class OneEuro:
    """One-euro filter over arrays; NaN inputs hold the last output."""

    def __init__(self, s: TriangulationSettings):
        self.s, self.x, self.dx, self.t = s, None, None, None

    @staticmethod
    def _alpha(cutoff, dt):
        tau = 1.0 / (2 * np.pi * cutoff)
        return 1.0 / (1.0 + tau / dt)

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        if self.x is None:
            self.x, self.dx, self.t = np.nan_to_num(x), np.zeros_like(x), t
            return self.x.copy()
        dt = max(t - self.t, 1e-6)
        x = np.where(np.isfinite(x), x, self.x)
        a_d = self._alpha(self.s.d_cutoff_hz, dt)
        self.dx = a_d * (x - self.x) / dt + (1 - a_d) * self.dx
        speed = np.linalg.norm(self.dx, axis=-1, keepdims=True)
        a = self._alpha(self.s.min_cutoff_hz + self.s.beta * speed, dt)
        self.x, self.t = a * x + (1 - a) * self.x, t
        return self.x.copy()


def _first_fit(skeleton, layout, targets, weights) -> np.ndarray:
    """The best of four headings from the rest pose placed at the points' centroid."""
    best, best_cost = None, np.inf
    for yaw in np.radians([0, 90, 180, 270]):
        theta = np.zeros(skeleton.pose_dim)
        theta[3:6] = [0, 0, yaw]
        rest = studio.site_positions(skeleton, layout.bones, layout.offsets, theta)
        theta[:3] = np.average(targets[weights > 0] - rest[weights > 0], axis=0)
        ok, theta = _core.fit_to_points(skeleton, layout.bones, layout.offsets, targets, weights, theta, 100)
        cost = np.sum(weights[:, None] * (studio.site_positions(skeleton, layout.bones, layout.offsets, theta) - targets) ** 2)
        if ok and cost < best_cost:
            best, best_cost = theta, cost
    return best if best is not None else np.zeros(skeleton.pose_dim)


def video_only(take, s: TriangulationSettings = TriangulationSettings()) -> np.ndarray:
    """(F, 66) poses from the detections alone, causally."""
    twins = detector.mirror(take.layout.names)
    smoother = OneEuro(s)
    thetas = np.zeros_like(take.thetas)
    theta = None
    for f, det in enumerate(take.keypoints):
        if det is not None:
            points, valid = triangulate(take.rig, det, s)
            det = fix_swaps(take.rig, det, points, valid, twins, s)
            points, valid = triangulate(take.rig, det, s)
            points = smoother(take.times[f], np.where(valid[:, None], points, np.nan))
            weights = valid.astype(float)  # points held from earlier frames are stale: no weight
            if theta is None and valid.sum() >= 6:
                theta = _first_fit(take.skeleton, take.layout, np.nan_to_num(points), weights)
            elif theta is not None:
                ok, fitted = _core.fit_to_points(take.skeleton, take.layout.bones, take.layout.offsets,
                                                 np.nan_to_num(points), weights, theta, 20)
                theta = fitted if ok else theta
        thetas[f] = theta if theta is not None else 0.0
    return thetas


