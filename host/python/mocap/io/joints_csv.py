"""Joint-position CSV: one row per frame, the world position of every bone origin.

Columns: frame, time_s, then <bone>_x, <bone>_y, <bone>_z for each bone in skeleton order;
metres, in our world frame (right-handed, Z up), six decimals (micrometres).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from mocap.errors import InputError
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


def read_positions_csv(path: str | Path) -> tuple[list[str], np.ndarray, np.ndarray]:
    """(point names, positions (F, J, 3) m, times (F,) s) of a CSV this module or `mocap solve
    --take` (joints.csv: <joint>_x, _y, _z) wrote. InputError naming the file and line for
    anything else."""
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise InputError(f"{path}: cannot read it as CSV: {e}") from None
    if len(rows) < 2:
        raise InputError(f"{path}: no frames (a header and one row per frame expected)")
    header = rows[0]
    points = [c[:-2] for c in header[2::3]]
    expected = ["frame", "time_s"] + [f"{p}_{a}" for p in points for a in "xyz"]
    if header != expected or not points or len(set(points)) != len(points):
        raise InputError(f"{path}:1: expected frame, time_s, then <name>_x, <name>_y, <name>_z per point, "
                         f"each name once; got {header[:8]}...")
    values = np.empty((len(rows) - 1, len(header)))
    for k, row in enumerate(rows[1:]):
        try:
            if len(row) != len(header):
                raise ValueError
            values[k] = [float(v) for v in row]
        except ValueError:
            raise InputError(f"{path}:{k + 2}: {len(row)} cells, expected {len(header)} numbers") from None
    if not np.isfinite(values).all():
        raise InputError(f"{path}:{2 + int(np.flatnonzero(~np.isfinite(values).all(axis=1))[0])}: not finite")
    if (np.diff(values[:, 1]) <= 0).any():
        raise InputError(f"{path}: time_s does not increase (line {int(np.argmax(np.diff(values[:, 1]) <= 0)) + 3})")
    return points, values[:, 2:].reshape(len(values), len(points), 3), values[:, 1]
