"""The cameras' first poses, before bundle adjustment: the pair that shares the most points
from their essential matrix (RANSAC), the others one by one by PnP (RANSAC) on the points
triangulated so far. Up to scale: the pair's baseline is the unit."""

from __future__ import annotations

import cv2
import numpy as np

from mocap import rotations
from mocap.calibration.rig.bundle import Cameras, Observations, sum_by
from mocap.calibration.rig.views import shared_counts
from mocap.errors import InputError

MIN_SHARED = 30  # points a camera must share with the cameras placed before it
RANSAC_PX = 6.0


def triangulate(cams: Cameras, obs: Observations, placed: np.ndarray, n_points: int) -> np.ndarray:
    """(P, 3) DLT of each point from its observations in the placed cameras (NaN with fewer than two)."""
    use = placed[obs.camera]
    proj = np.concatenate([cams.rotation, cams.translation[:, :, None]], axis=2)[obs.camera[use]]  # (n, 3, 4)
    u, v = obs.uv[use, 0:1], obs.uv[use, 1:2]
    rows = np.stack([u * proj[:, 2] - proj[:, 0], v * proj[:, 2] - proj[:, 1]], axis=1)  # (n, 2, 4)
    rows *= np.sqrt(obs.weight[use])[:, None, None]
    ata = sum_by(obs.point[use], np.swapaxes(rows, 1, 2) @ rows, n_points)
    views = np.bincount(obs.point[use], minlength=n_points)
    _, vecs = np.linalg.eigh(ata + 1e-12 * np.eye(4))
    h = vecs[:, :, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        points = h[:, :3] / h[:, 3:4]
    points[views < 2] = np.nan
    return points


def _pair(obs: Observations, a: int, b: int) -> tuple[np.ndarray, np.ndarray]:
    ia = np.full(obs.point.max() + 1, -1)
    ib = ia.copy()
    ia[obs.point[obs.camera == a]] = np.flatnonzero(obs.camera == a)
    ib[obs.point[obs.camera == b]] = np.flatnonzero(obs.camera == b)
    both = (ia >= 0) & (ib >= 0)
    return obs.uv[ia[both]], obs.uv[ib[both]]


def _first_pair(obs: Observations, counts: np.ndarray, names: list[str]) -> tuple[int, int, Cameras]:
    shared = counts.copy()
    np.fill_diagonal(shared, 0)
    a, b = np.unravel_index(np.argmax(shared), shared.shape)
    if shared[a, b] < MIN_SHARED:
        raise InputError(f"no two cameras saw {MIN_SHARED} keypoints of the person on the same frames "
                         f"(most: {names[a]} and {names[b]}, {shared[a, b]})")
    ua, ub = _pair(obs, a, b)
    threshold = RANSAC_PX / float(np.mean(obs.focal[[a, b]]))
    e, mask = cv2.findEssentialMat(ua, ub, np.eye(3), method=cv2.RANSAC, prob=0.999, threshold=threshold)
    if e is None or e.shape != (3, 3):
        raise InputError(f"cameras {names[a]} and {names[b]}: no relative pose fits their shared keypoints")
    _, r, t, _ = cv2.recoverPose(e, ua, ub, np.eye(3), mask=mask)
    c = len(counts)
    cams = Cameras(np.tile(np.eye(3), (c, 1, 1)), np.zeros((c, 3)))
    cams.rotation[b], cams.translation[b] = r, t.ravel()
    return a, b, cams


def initial(obs: Observations, names: list[str]) -> tuple[Cameras, np.ndarray, int]:
    """Every camera's pose (world: the first pair's first camera, baseline 1), the points
    triangulated from them, and the index of the camera that defines the world."""
    counts = shared_counts(obs, len(names))
    a, b, cams = _first_pair(obs, counts, names)
    placed = np.zeros(len(names), dtype=bool)
    placed[[a, b]] = True
    n_points = obs.point.max() + 1
    points = triangulate(cams, obs, placed, n_points)
    while not placed.all():
        known = np.isfinite(points[:, 0])
        reach = [((obs.camera == c) & known[obs.point]).sum() if not placed[c] else -1 for c in range(len(names))]
        c = int(np.argmax(reach))
        if reach[c] < MIN_SHARED:
            raise InputError(f"camera {names[c]}: sees {reach[c]} keypoints the other cameras placed so far "
                             f"also see ({MIN_SHARED} needed to place it)")
        mine = np.flatnonzero((obs.camera == c) & known[obs.point])
        ok, rvec, tvec, _ = cv2.solvePnPRansac(points[obs.point[mine]], obs.uv[mine], np.eye(3), None,
                                               reprojectionError=RANSAC_PX / obs.focal[c], iterationsCount=200,
                                               flags=cv2.SOLVEPNP_EPNP)
        if not ok:
            raise InputError(f"camera {names[c]}: no pose fits the keypoints it shares with the others")
        cams.rotation[c], cams.translation[c] = rotations.exp(rvec.ravel()), tvec.ravel()
        placed[c] = True
        points = triangulate(cams, obs, placed, n_points)
    return cams, points, int(a)
