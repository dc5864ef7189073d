"""Checks shared by the file writers: pose sequences are (frames, pose_dim) and finite."""

from __future__ import annotations

import numpy as np


def checked_thetas(skeleton, thetas) -> np.ndarray:
    """(F, pose_dim) float array; ValueError naming the first frame with a non-finite value."""
    thetas = np.asarray(thetas, dtype=float)
    if thetas.ndim != 2 or thetas.shape[1] != skeleton.pose_dim:
        raise ValueError(f"thetas must be (frames, {skeleton.pose_dim}), got {thetas.shape}")
    bad = np.flatnonzero(~np.isfinite(thetas).all(axis=1))
    if bad.size:
        raise ValueError(f"frame {bad[0]}: theta is not finite ({bad.size} bad frames)")
    return thetas
