"""C3D writer (ezc3d): marker trajectories -> a C3D file, as motion-capture and
biomechanics tools (Vicon Nexus, Visual3D, OpenSim's C3D reader, Mokka) open it.

Conventions of the file written: POINT:UNITS "mm" (positions written in millimetres, 32-bit
floats), the axes of the markers given (ours: Z up, right-handed), POINT:RATE the frame rate,
POINT:LABELS the marker names; a missing (NaN) marker is written as C3D marks one: residual -1.
"""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np


def write_c3d(path: str | Path, names: list[str], markers: np.ndarray, rate: float) -> None:
    """markers (F, M, 3) metres at `rate` Hz. ValueError for a shape, name or rate that makes no file."""
    markers = np.asarray(markers, dtype=float)
    if markers.ndim != 3 or markers.shape[1:] != (len(names), 3) or not len(markers):
        raise ValueError(f"markers must be (F > 0, {len(names)}, 3), got {markers.shape}")
    if not names or len(set(names)) != len(names) or any(not n.strip() for n in names):
        raise ValueError(f"marker names must be unique and non-empty: {names}")
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"rate {rate} must be positive")
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [float(rate)]
    c["parameters"]["POINT"]["LABELS"]["value"] = tuple(names)
    c["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    points = np.ones((4, len(names), len(markers)))
    points[:3] = 1000.0 * markers.transpose(2, 1, 0)
    c["data"]["points"] = points
    c.write(str(path))
