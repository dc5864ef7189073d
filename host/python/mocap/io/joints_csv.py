"""Joint-position CSV: one row per frame, the world position of every bone origin.

Columns: frame, time_s, then <bone>_x, <bone>_y, <bone>_z for each bone in skeleton order;
metres, in our world frame (right-handed, Z up), six decimals (micrometres).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from mocap.io._thetas import checked_thetas


def write_joints_csv(path: str | Path, skeleton, thetas, times) -> None:
    """Write the joint positions of poses thetas (F, pose_dim) at times (F,) seconds."""
    thetas = checked_thetas(skeleton, thetas)
    positions = np.array([skeleton.forward_kinematics(theta)[1] for theta in thetas]).reshape(len(thetas), -1, 3)
    write_positions_csv(path, skeleton.bone_names, positions, times)


def write_positions_csv(path: str | Path, bone_names: list[str], positions, times) -> None:
    """Write bone origins (F, J, 3) m, e.g. as the host published them, at times (F,) seconds."""
    positions = np.asarray(positions, dtype=float)
    times = np.asarray(times, dtype=float)
    if positions.ndim != 3 or positions.shape[1:] != (len(bone_names), 3):
        raise ValueError(f"positions must be (F, {len(bone_names)}, 3), got {positions.shape}")
    if times.shape != (len(positions),):
        raise ValueError(f"times must be ({len(positions)},), got {times.shape}")
    for what, values in (("time", times), ("position", positions.reshape(len(positions), -1))):
        bad = np.flatnonzero(~np.isfinite(values).reshape(len(values), -1).all(axis=1))
        if bad.size:
            raise ValueError(f"frame {bad[0]}: {what} is not finite")
    header = ["frame", "time_s"] + [f"{name}_{axis}" for name in bone_names for axis in "xyz"]
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        for frame, (p, time_s) in enumerate(zip(positions, times)):
            writer.writerow([frame, f"{time_s:.6f}", *(f"{v:.6f}" for v in p.ravel())])
