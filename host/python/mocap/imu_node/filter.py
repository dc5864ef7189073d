"""The node's orientation filter (firmware/core/imu_filter.h) on the host, through ctypes.

The library is ``libmocap_node.so`` beside this file, built by the CMake target
``mocap_node`` (``make build``). :class:`Settings` mirrors ``imu_filter_settings_t`` field
for field; the C side reports its size so a mismatch is caught at load time.

- :func:`run`: a fresh filter over a recording (numpy arrays), its quaternions and flags.
- :func:`read_csv` / :func:`sample_period` / :func:`write_csv` / :func:`filter_csv`:
  ``mocap imu-filter`` (CSV in, CSV out; the period is the median dt, each dt within
  PERIOD_TOLERANCE of it; a NaN sensor value makes the filter skip that vector).
"""

from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mocap.errors import InputError, MocapError

LIBRARY = Path(__file__).with_name("libmocap_node.so")
FLAG_REST, FLAG_HELD, FLAG_SETTLED = 0x01, 0x02, 0x04  # imu_filter_batch.h
CSV_COLUMNS = ("t", "gx", "gy", "gz", "ax", "ay", "az", "mx", "my", "mz")
PERIOD_TOLERANCE = 0.05  # every dt within 5 % of the median dt


class Settings(ctypes.Structure):
    """``imu_filter_settings_t``: units in the C header (SI, angles in rad)."""

    _fields_ = [
        ("acc_time_constant_s", ctypes.c_float),
        ("acc_damping", ctypes.c_float),
        ("mag_time_constant_s", ctypes.c_float),
        ("rest_time_s", ctypes.c_float),
        ("rest_filter_time_constant_s", ctypes.c_float),
        ("rest_gyr_threshold_rads", ctypes.c_float),
        ("rest_acc_threshold_mps2", ctypes.c_float),
        ("bias_limit_rads", ctypes.c_float),
        ("bias_sigma_init_rads", ctypes.c_float),
        ("bias_sigma_motion_rads", ctypes.c_float),
        ("bias_sigma_rest_rads", ctypes.c_float),
        ("bias_forgetting_time_s", ctypes.c_float),
        ("bias_vertical_forgetting", ctypes.c_float),
        ("bias_update_rate_hz", ctypes.c_float),
        ("mag_current_time_constant_s", ctypes.c_float),
        ("mag_ref_time_constant_s", ctypes.c_float),
        ("mag_norm_threshold", ctypes.c_float),
        ("mag_dip_threshold_rad", ctypes.c_float),
        ("mag_new_time_s", ctypes.c_float),
        ("mag_new_first_time_s", ctypes.c_float),
        ("mag_new_min_gyr_rads", ctypes.c_float),
        ("mag_min_undisturbed_time_s", ctypes.c_float),
        ("mag_max_rejection_time_s", ctypes.c_float),
        ("mag_rejection_factor", ctypes.c_float),
        ("motion_bias_enabled", ctypes.c_bool),
        ("rest_bias_enabled", ctypes.c_bool),
        ("mag_rejection_enabled", ctypes.c_bool),
    ]

    def as_dict(self) -> dict[str, float | bool]:
        return {name: getattr(self, name) for name, _ in self._fields_}


class LibraryMissingError(MocapError):
    pass


_lib: ctypes.CDLL | None = None


def library() -> ctypes.CDLL:
    """The loaded library, its prototypes declared and its settings size checked."""
    global _lib
    if _lib is not None:
        return _lib
    if not LIBRARY.exists():
        raise LibraryMissingError(f"{LIBRARY} is not built: run make build (CMake target mocap_node)")
    lib = ctypes.CDLL(str(LIBRARY))
    floats = np.ctypeslib.ndpointer(np.float32, flags="C_CONTIGUOUS")
    lib.imu_filter_batch_settings_size.restype = ctypes.c_size_t
    lib.imu_filter_batch_state_size.restype = ctypes.c_size_t
    lib.imu_filter_batch_default_settings.argtypes = [ctypes.POINTER(Settings)]
    lib.imu_filter_batch_default_settings.restype = None
    lib.imu_filter_batch_run.argtypes = [ctypes.POINTER(Settings), ctypes.c_float, floats, floats, ctypes.c_void_p,
                                         ctypes.c_size_t, floats, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
    lib.imu_filter_batch_run.restype = ctypes.c_int64
    size = lib.imu_filter_batch_settings_size()
    if size != ctypes.sizeof(Settings):
        raise LibraryMissingError(f"{LIBRARY}: imu_filter_settings_t is {size} bytes, the Python mirror "
                                  f"{ctypes.sizeof(Settings)}: update mocap.imu_node.filter.Settings and rebuild")
    _lib = lib
    return lib


def default_settings() -> Settings:
    """``imu_filter_settings_default``."""
    settings = Settings()
    library().imu_filter_batch_default_settings(ctypes.byref(settings))
    return settings


@dataclass
class Result:
    quaternions: np.ndarray  # (n, 4) w, x, y, z, sensor -> ENU (6D: heading from the gyroscope)
    quaternions_6d: np.ndarray  # (n, 4) sensor -> E6 (inclination only)
    bias_rads: np.ndarray  # (n, 3) gyroscope bias estimate
    flags: np.ndarray  # (n,) uint8, FLAG_*
    rejected: int  # input vectors the filter skipped as bad


def _vectors(name: str, values: np.ndarray | None, n: int | None = None) -> np.ndarray:
    array = np.ascontiguousarray(values, dtype=np.float32)
    if array.ndim != 2 or array.shape[1] != 3 or (n is not None and len(array) != n):
        raise InputError(f"{name}: expected an (n, 3) array{'' if n is None else f' with n = {n}'}, got {array.shape}")
    return array


def run(gyr_rads: np.ndarray, acc_mps2: np.ndarray, mag_ut: np.ndarray | None, sample_period_s: float,
        settings: Settings | None = None) -> Result:
    """A fresh filter over n samples (sensor frame); ``mag_ut`` None runs it 6D."""
    lib = library()
    gyr = _vectors("gyr", gyr_rads)
    n = len(gyr)
    acc = _vectors("acc", acc_mps2, n)
    mag = None if mag_ut is None else _vectors("mag", mag_ut, n)
    settings = default_settings() if settings is None else settings
    q = np.empty((n, 4), np.float32)
    q6 = np.empty((n, 4), np.float32)
    bias = np.empty((n, 3), np.float32)
    flags = np.empty(n, np.uint8)
    rejected = lib.imu_filter_batch_run(ctypes.byref(settings), float(sample_period_s), gyr, acc,
                                        None if mag is None else mag.ctypes.data, n, q, q6.ctypes.data,
                                        bias.ctypes.data, flags.ctypes.data)
    if rejected < 0:
        raise InputError(f"the filter refused its settings or the sample period {sample_period_s!r} s")
    return Result(q, q6, bias, flags, int(rejected))


@dataclass
class Recording:
    t: np.ndarray  # (n,) s
    samples: np.ndarray  # (n, 9) gx gy gz (rad/s), ax ay az (m/s²), mx my mz (µT)
    lines: np.ndarray  # (n,) the file line of each row (1-based), for messages


def read_csv(path: str | Path) -> Recording:
    """``t, gx, gy, gz, ax, ay, az, mx, my, mz`` with a header row (any column order; extra
    columns ignored; blank lines skipped). A sensor value may be NaN or empty (the filter
    skips that vector); an error names the file and line of anything else wrong."""
    path = Path(path)
    with path.open() as f:
        lines = f.read().splitlines()
    if not lines:
        raise InputError(f"{path}: empty file, expected a header row {','.join(CSV_COLUMNS)}")
    header = [name.strip() for name in lines[0].split(",")]
    missing = [name for name in CSV_COLUMNS if name not in header]
    if missing:
        raise InputError(f"{path}:1: missing column(s) {', '.join(missing)} (header: {lines[0]!r})")
    index = [header.index(name) for name in CSV_COLUMNS]
    rows, numbers = [], []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        cells = line.split(",")
        if len(cells) != len(header):
            raise InputError(f"{path}:{number}: {len(cells)} values, the header has {len(header)}")
        try:
            row = [float(cells[i]) if cells[i].strip() else math.nan for i in index]
        except ValueError as e:
            raise InputError(f"{path}:{number}: not a number ({e})") from None
        if not math.isfinite(row[0]):
            raise InputError(f"{path}:{number}: t is not a finite number")
        rows.append(row)
        numbers.append(number)
    if len(rows) < 2:
        raise InputError(f"{path}: {len(rows)} sample row(s), at least 2 are needed to know the rate")
    table = np.array(rows)
    return Recording(table[:, 0], table[:, 1:], np.array(numbers))


def sample_period(recording: Recording, path: str | Path = "input") -> float:
    """The median dt, refusing time that does not increase or steps that differ from it by
    more than PERIOD_TOLERANCE (the filter runs at one fixed period)."""
    t, lines = recording.t, recording.lines
    dt = np.diff(t)
    bad = np.flatnonzero(~(dt > 0))
    if bad.size:
        i = bad[0]
        raise InputError(f"{path}:{lines[i + 1]}: t does not increase ({t[i]!r} then {t[i + 1]!r})")
    period = float(np.median(dt))
    off = np.flatnonzero(np.abs(dt - period) > PERIOD_TOLERANCE * period)
    if off.size:
        i = off[0]
        raise InputError(f"{path}:{lines[i + 1]}: irregular sampling: dt {dt[i]:.6g} s vs the median {period:.6g} s "
                         f"(more than {PERIOD_TOLERANCE:.0%} off); resample the recording first")
    return period


def write_csv(path: str | Path, t: np.ndarray, quaternions: np.ndarray) -> None:
    with Path(path).open("w") as f:
        f.write("t,qw,qx,qy,qz\n")
        for time, q in zip(t, quaternions.astype(float)):
            f.write(f"{time:.9g},{q[0]:.9g},{q[1]:.9g},{q[2]:.9g},{q[3]:.9g}\n")


def filter_csv(path_in: str | Path, path_out: str | Path, use_mag: bool = True) -> dict[str, float | int | str]:
    """``mocap imu-filter``: the node's filter over a CSV recording, written as a CSV."""
    recording = read_csv(path_in)
    period = sample_period(recording, path_in)
    samples = recording.samples
    result = run(samples[:, 0:3], samples[:, 3:6], samples[:, 6:9] if use_mag else None, period)
    write_csv(path_out, recording.t, result.quaternions)
    return {"out": str(path_out), "samples": len(recording.t), "sample_period_s": period,
            "mode": "9D" if use_mag else "6D", "rejected_vectors": result.rejected,
            "settled_at_s": _settled_at(recording.t, result.flags)}


def _settled_at(t: np.ndarray, flags: np.ndarray) -> float | None:
    settled = np.flatnonzero(flags & FLAG_SETTLED)
    return float(t[settled[0]] - t[0]) if settled.size else None
