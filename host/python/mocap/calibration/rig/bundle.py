"""Bundle adjustment of camera poses and 3D points from normalised image observations.

Levenberg-Marquardt on the reprojection error in pixels (each camera's normalised
coordinates times its focal length), Cauchy-weighted by iteratively reweighted least
squares and by the detections' confidences. The points are eliminated per step (each is
seen by a handful of cameras: a 3x3 block each), leaving the cameras' 6C x 6C Schur
complement. One camera is held fixed; the scale stays free (mocap.calibration.rig.world sets it).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap import rotations


@dataclasses.dataclass
class Observations:
    camera: np.ndarray  # (N,) camera index
    point: np.ndarray  # (N,) point index
    uv: np.ndarray  # (N, 2) normalised image coordinates (undistorted)
    weight: np.ndarray  # (N,) detection confidence
    focal: np.ndarray  # (C,) pixels per normalised unit, for pixel residuals


@dataclasses.dataclass
class Cameras:
    rotation: np.ndarray  # (C, 3, 3) world -> camera
    translation: np.ndarray  # (C, 3)


def residuals(cams: Cameras, points: np.ndarray, obs: Observations) -> tuple[np.ndarray, np.ndarray]:
    """(N, 2) pixel residuals and (N, 3) camera-frame points of every observation."""
    p = np.einsum("nij,nj->ni", cams.rotation[obs.camera], points[obs.point]) + cams.translation[obs.camera]
    with np.errstate(divide="ignore", invalid="ignore"):
        r = (p[:, :2] / p[:, 2:3] - obs.uv) * obs.focal[obs.camera, None]
    return r, p


def _jacobians(cams: Cameras, p: np.ndarray, obs: Observations) -> tuple[np.ndarray, np.ndarray]:
    """(N, 2, 6) d r / d(rotation increment, translation) and (N, 2, 3) d r / d point."""
    z = p[:, 2]
    dproj = np.zeros((len(p), 2, 3))
    dproj[:, 0, 0] = dproj[:, 1, 1] = 1.0 / z
    dproj[:, :, 2] = -p[:, :2] / z[:, None] ** 2
    dproj *= obs.focal[obs.camera, None, None]
    rotated = p - cams.translation[obs.camera]  # R X: the left increment exp(d) R turns it by d x R X
    skew = np.zeros((len(p), 3, 3))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -rotated[:, 2], rotated[:, 1], -rotated[:, 0]
    skew -= np.swapaxes(skew, 1, 2)
    j_cam = np.concatenate([dproj @ -skew, dproj], axis=2)
    return j_cam, dproj @ cams.rotation[obs.camera]


def cauchy_weights(r: np.ndarray, obs: Observations, scale_px: float) -> np.ndarray:
    """(N,) IRLS weights: confidence times the Cauchy loss's 1 / (1 + (|r| / s)^2)."""
    return obs.weight / (1.0 + (r ** 2).sum(axis=1) / scale_px ** 2)


def sum_by(index: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """(n, ...) sums of values (N, ...) grouped by index (N,) (np.add.at, faster)."""
    flat = values.reshape(len(values), -1)
    out = np.stack([np.bincount(index, flat[:, k], minlength=n) for k in range(flat.shape[1])], axis=1)
    return out.reshape((n,) + values.shape[1:])


def _normal_equations(cams, points, obs, w):
    r, p = residuals(cams, points, obs)
    j_cam, j_pt = _jacobians(cams, p, obs)
    c, n_pts = len(cams.rotation), len(points)
    wj_cam, wj_pt = w[:, None, None] * j_cam, w[:, None, None] * j_pt
    h_cc = sum_by(obs.camera, np.swapaxes(j_cam, 1, 2) @ wj_cam, c)
    g_c = sum_by(obs.camera, np.einsum("nki,nk->ni", wj_cam, r), c)
    h_pp = sum_by(obs.point, np.swapaxes(j_pt, 1, 2) @ wj_pt, n_pts)
    g_p = sum_by(obs.point, np.einsum("nki,nk->ni", wj_pt, r), n_pts)
    h_cp = np.swapaxes(j_cam, 1, 2) @ wj_pt  # (N, 6, 3): one camera-point pair per observation
    return h_cc, g_c, h_pp, g_p, h_cp


def _step(cams, points, obs, w, damping, pairs, fixed):
    """The LM step (camera increments (C, 6), point increments (P, 3)) with camera `fixed` held."""
    h_cc, g_c, h_pp, g_p, h_cp = _normal_equations(cams, points, obs, w)
    c = len(cams.rotation)
    h_pp = h_pp + damping * (np.einsum("pii->pi", h_pp)[:, :, None] * np.eye(3) + 1e-9 * np.eye(3))
    h_pp_inv = np.linalg.inv(h_pp)
    a = h_cp @ h_pp_inv[obs.point]  # (N, 6, 3)
    i, j = pairs
    s = sum_by(obs.camera[i] * c + obs.camera[j], a[i] @ np.swapaxes(h_cp[j], 1, 2), c * c).reshape(c, c, 6, 6)
    big = -s.transpose(0, 2, 1, 3).reshape(6 * c, 6 * c)
    for k in range(c):
        big[6 * k:6 * k + 6, 6 * k:6 * k + 6] += h_cc[k] + damping * np.diag(np.diag(h_cc[k]) + 1e-9)
    rhs = sum_by(obs.camera, np.einsum("nij,nj->ni", a, g_p[obs.point]), c) - g_c
    free = np.repeat(np.arange(c) != fixed, 6)
    dc = np.zeros(6 * c)
    dc[free] = np.linalg.solve(big[np.ix_(free, free)], rhs.ravel()[free])
    dc = dc.reshape(c, 6)
    back = g_p + sum_by(obs.point, np.einsum("nji,nj->ni", h_cp, dc[obs.camera]), len(points))
    return dc, -np.einsum("pij,pj->pi", h_pp_inv, back)


def _apply(cams: Cameras, points: np.ndarray, dc: np.ndarray, dp: np.ndarray) -> tuple[Cameras, np.ndarray]:
    turn = np.array([rotations.exp(d) for d in dc[:, :3]])
    return Cameras(turn @ cams.rotation, cams.translation + dc[:, 3:]), points + dp


def observation_pairs(obs: Observations) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (i, j) of observations of the same point (i == j included)."""
    order = np.argsort(obs.point, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(obs.point[order]) != 0])
    counts = np.diff(np.r_[starts, len(order)])
    i, j = [], []
    for n in np.unique(counts):
        groups = order[starts[counts == n][:, None] + np.arange(n)]  # (G, n)
        i.append(np.repeat(groups, n, axis=1).ravel())
        j.append(np.tile(groups, (1, n)).ravel())
    return np.concatenate(i), np.concatenate(j)


def adjust(cams: Cameras, points: np.ndarray, obs: Observations, scale_px: float = 3.0,
           iterations: int = 50, fixed: int = 0) -> tuple[Cameras, np.ndarray, np.ndarray]:
    """Cameras, points and each observation's final Cauchy weight after bundle adjustment
    (camera `fixed` held where it is)."""
    pairs = observation_pairs(obs)
    damping = 1e-3

    def cost(c, x):
        r, p = residuals(c, x, obs)
        if not np.isfinite(r).all() or (p[:, 2] <= 0).any():
            return np.inf
        return float((obs.weight * np.log1p((r ** 2).sum(axis=1) / scale_px ** 2)).sum())

    current = cost(cams, points)
    for _ in range(iterations):
        w = cauchy_weights(residuals(cams, points, obs)[0], obs, scale_px)
        dc, dp = _step(cams, points, obs, w, damping, pairs, fixed)
        trial_cams, trial_points = _apply(cams, points, dc, dp)
        trial = cost(trial_cams, trial_points)
        if trial < current:
            done = current - trial < 1e-5 * current
            cams, points, current, damping = trial_cams, trial_points, trial, max(damping / 3, 1e-7)
            if done:
                break
        else:
            damping *= 4
            if damping > 1e6:
                break
    return cams, points, cauchy_weights(residuals(cams, points, obs)[0], obs, scale_px)
