"""What users would pick instead of the fused solver, scored by the same evaluation.

IMU only (imu_only): the IMU orientations drive forward kinematics, as a suit without
position aiding does.

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

import numpy as np

from mocap import _core, rotations
from mocap.model import studio
from mocap.model.triangulation import TriangulationSettings, reprojection_error, triangulate
from mocap.sim import detector
from mocap.sim.take import Take


def fix_swaps(rig: _core.Rig, det: np.ndarray, points: np.ndarray, valid: np.ndarray, twins: np.ndarray,
              s: TriangulationSettings) -> np.ndarray:
    """Detections with each camera mirrored where the mirror reprojects markedly better."""
    out = det.copy()
    err = reprojection_error(rig, points, det[..., :2])
    err_m = reprojection_error(rig, points, det[:, twins, :2])
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


def imu_only(t: Take) -> np.ndarray:
    """Baseline: IMU orientations drive forward kinematics (bones without a sensor follow
    their parent), the root held at the true position, as an IMU suit without position
    aiding scored after aligning the root."""
    parents = t.skeleton.parents
    world = rotations.matrix_from_quaternion(t.quaternions)  # (F, M, 3, 3) sensor -> reference
    reference = np.array([s.reference for s in t.imus])
    mount = np.array([s.mount for s in t.imus])
    bone_world = reference[None] @ world @ np.swapaxes(mount, -1, -2)[None]  # R_ig R_i R_m^T
    thetas = np.zeros_like(t.thetas)
    thetas[:, :3] = t.thetas[:, :3]
    by_bone = {s.bone: i for i, s in enumerate(t.imus)}
    for f in range(len(thetas)):
        g = np.empty((len(parents), 3, 3))
        for b, p in enumerate(parents):
            g[b] = bone_world[f, by_bone[b]] if b in by_bone else (g[p] if p >= 0 else np.eye(3))
            local = g[b] if p < 0 else g[p].T @ g[b]
            thetas[f, 3 + 3 * b : 6 + 3 * b] = rotations.log(local)
    return thetas
