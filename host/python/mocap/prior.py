"""PCA pose prior over the non-root DOF (slide "Pose prior terms")."""

from __future__ import annotations

import numpy as np

from mocap import _core


def fit(poses: np.ndarray, variance: float = 0.95) -> _core.PosePrior:
    """PCA of (N, 66) pose vectors' non-root DOF keeping `variance` of the total."""
    bar = np.asarray(poses, dtype=float)[:, 6:]
    mean = bar.mean(axis=0)
    _, s, vt = np.linalg.svd(bar - mean, full_matrices=False)
    var = s**2 / max(len(bar) - 1, 1)
    k = int(np.searchsorted(np.cumsum(var) / var.sum(), variance) + 1)
    k = min(k, bar.shape[1] - 1)
    sigma = np.sqrt(np.maximum(var[:k], 1e-12))
    return _core.PosePrior(mean, vt[:k].T.copy(), sigma)
