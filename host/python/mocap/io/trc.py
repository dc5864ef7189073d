"""TRC marker files (OpenSim, Pose2Sim): tab-separated, five header lines (DataRate and
Units on the third), then Frame#, Time and X Y Z per marker."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from mocap.errors import InputError

UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}


@dataclasses.dataclass(frozen=True)
class Trc:
    rate: float  # Hz
    names: list[str]
    markers: np.ndarray  # (F, M, 3) metres, the file's axes; NaN where missing
    times: np.ndarray  # (F,) s


def _number(cell: str, where: str) -> float:
    try:
        return float(cell) if cell.strip() else float("nan")
    except ValueError:
        raise InputError(f"{where}: {cell!r} is not a number") from None


def read_trc(path: Path) -> Trc:
    """A TRC file (tab-separated: 5 header lines, then Frame#, Time, X Y Z per marker).
    Empty or NaN cells, and cells missing at the end of a row, are missing markers."""
    lines = Path(path).read_text().splitlines()
    if len(lines) < 6:
        raise InputError(f"{path}: {len(lines)} lines, not a TRC file (5 header lines and data)")
    keys, values = lines[1].split("\t"), lines[2].split("\t")
    header = dict(zip((k.strip() for k in keys), (v.strip() for v in values)))
    if "DataRate" not in header or header.get("Units") not in UNITS:
        raise InputError(f"{path}:3: needs DataRate and Units in {sorted(UNITS)}, got {header}")
    rate, scale = _number(header["DataRate"], f"{path}:3: DataRate"), UNITS[header["Units"]]
    names = [c.strip() for c in lines[3].split("\t")[2:] if c.strip()]
    if header.get("NumMarkers", str(len(names))) != str(len(names)):
        raise InputError(f"{path}:4: {len(names)} marker names, NumMarkers says {header['NumMarkers']}")
    rows = []
    for number, line in enumerate(lines[5:], start=6):
        if not line.strip():
            continue
        cells = line.rstrip().split("\t")
        if len(cells) > 2 + 3 * len(names):
            raise InputError(f"{path}:{number}: {len(cells)} cells, more than Frame#, Time and {len(names)} markers")
        cells += [""] * (2 + 3 * len(names) - len(cells))
        rows.append([_number(c, f"{path}:{number}, column {k + 1}") for k, c in enumerate(cells)])
    if not rows or not rate > 0:
        raise InputError(f"{path}: no data rows or DataRate {rate} not positive")
    data = np.array(rows)
    return Trc(rate, names, data[:, 2:].reshape(len(rows), len(names), 3) * scale, data[:, 1])
