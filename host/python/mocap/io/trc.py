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


# Joint centres (mocap.model.joint_centres.JOINTS) -> the markers of Pose2Sim's TRC, which
# its OpenSim models are scaled and driven with (triangulated BODY_25B keypoints). Our "head"
# joint is the head bone's origin, the top of the neck: BODY_25B's UpperNeck, "Neck" in the
# TRC, not its HeadTop ("Head").
POSE2SIM_MARKERS = {"head": "Neck", "left_shoulder": "LShoulder", "right_shoulder": "RShoulder",
                    "left_elbow": "LElbow", "right_elbow": "RElbow", "left_wrist": "LWrist", "right_wrist": "RWrist",
                    "left_hip": "LHip", "right_hip": "RHip", "left_knee": "LKnee", "right_knee": "RKnee",
                    "left_ankle": "LAnkle", "right_ankle": "RAnkle"}


def write_trc(path: str | Path, names: list[str], markers: np.ndarray, rate: float, times: np.ndarray | None = None,
              units: str = "m") -> None:
    """A TRC file as Pose2Sim writes it for OpenSim: markers (F, M, 3) in metres, in the file's
    axes (OpenSim's: Y up), written in `units`, six decimals; frames numbered from 1, at `times`
    (s; default k / rate); a missing (NaN) marker is an empty cell. ValueError for a shape,
    name, rate or time that makes no file."""
    markers = np.asarray(markers, dtype=float)
    times = np.arange(len(markers)) / rate if times is None else np.asarray(times, dtype=float)
    if times.shape != (len(markers),) or not np.isfinite(times).all():
        raise ValueError(f"times must be ({len(markers)},) and finite")
    if markers.ndim != 3 or markers.shape[1:] != (len(names), 3):
        raise ValueError(f"markers must be (F, {len(names)}, 3), got {markers.shape}")
    if not names or len(set(names)) != len(names) or any(not n or n != n.strip() or "\t" in n for n in names):
        raise ValueError(f"marker names must be unique and non-empty, without tabs or edge spaces: {names}")
    if not (np.isfinite(rate) and rate > 0) or units not in UNITS:
        raise ValueError(f"rate {rate} must be positive and units one of {sorted(UNITS)}")
    scaled = markers / UNITS[units]
    lines = [f"PathFileType\t4\t(X/Y/Z)\t{Path(path).name}",
             "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames",
             f"{rate:g}\t{rate:g}\t{len(markers)}\t{len(names)}\t{units}\t{rate:g}\t1\t{len(markers)}",
             "Frame#\tTime\t" + "".join(f"{n}\t\t\t" for n in names).rstrip("\t"),
             "\t\t" + "\t".join(f"X{k}\tY{k}\tZ{k}" for k in range(1, len(names) + 1))]
    for f, frame in enumerate(scaled):
        cells = ["" if not np.isfinite(v) else f"{v:.6f}" for v in frame.reshape(-1)]
        lines.append("\t".join([str(f + 1), f"{times[f]:.6f}", *cells]))
    Path(path).write_text("\n".join(lines) + "\n")
