"""Joint-position CSV: one row per frame, the world position of every bone origin.

Columns: frame, time_s, then <bone>_x, <bone>_y, <bone>_z for each bone in skeleton order;
metres, in our world frame (right-handed, Z up), six decimals (micrometres).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from mocap.export._thetas import checked_thetas


def write_joints_csv(path: str | Path, skeleton, thetas, times) -> None:
    """Write the joint positions of poses thetas (F, pose_dim) at times (F,) seconds."""
    thetas = checked_thetas(skeleton, thetas)
    times = np.asarray(times, dtype=float)
    if times.shape != (len(thetas),):
        raise ValueError(f"times must be ({len(thetas)},), got {times.shape}")
    bad = np.flatnonzero(~np.isfinite(times))
    if bad.size:
        raise ValueError(f"frame {bad[0]}: time is not finite")
    header = ["frame", "time_s"] + [f"{name}_{axis}" for name in skeleton.bone_names for axis in "xyz"]
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        for frame, (theta, time_s) in enumerate(zip(thetas, times)):
            _, positions = skeleton.forward_kinematics(theta)
            writer.writerow([frame, f"{time_s:.6f}", *(f"{v:.6f}" for v in positions.ravel())])
