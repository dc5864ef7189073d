"""The node's orientation filter (firmware/core/imu_filter.h) for the hub's own IMUs, through
ctypes: one algorithm on the node, the host and the hub. The streaming entry points are
firmware/host/imu_filter_stream.h; the state is a caller-owned buffer of the size the library
reports, so Python mirrors no C struct (settings: the C defaults, or any ctypes structure of
the library's settings size, e.g. the host's ``mocap.imu_node.filter.Settings``).

The library, ``libmocap_node.so`` (CMake target ``mocap_node``, ``make build``), is found at
``$MOCAP_NODE_LIBRARY`` if set; else beside this module (the build copies it there: an edge box
installs the edge package without the host's); else where the build writes it for the host,
host/python/mocap/imu_node/ of this repository (a checkout where only the host's copy exists).
The edge may not import the host package beyond ``mocap.net``, so this binding is its own.
"""

from __future__ import annotations

import ctypes
import os
from pathlib import Path
from typing import Sequence

from mocap_edge.errors import EdgeError

LIBRARY_NAME = "libmocap_node.so"
REPO_LIBRARY = Path(__file__).resolve().parents[5] / "host" / "python" / "mocap" / "imu_node" / LIBRARY_NAME
FLAG_REST, FLAG_HELD, FLAG_SETTLED = 0x01, 0x02, 0x04  # IMU_FILTER_BATCH_* (imu_filter_batch.h)

Floats3 = ctypes.c_float * 3
Floats4 = ctypes.c_float * 4


class FilterLibraryError(EdgeError):
    """libmocap_node.so is not found or does not have the streaming entry points."""


def library_path() -> Path:
    """Where the library is looked for (module docstring); the first candidate that exists."""
    env = os.environ.get("MOCAP_NODE_LIBRARY")
    candidates = [Path(env)] if env else [Path(__file__).with_name(LIBRARY_NAME), REPO_LIBRARY]
    for path in candidates:
        if path.is_file():
            return path
    raise FilterLibraryError(f"{LIBRARY_NAME} not found (looked at {', '.join(map(str, candidates))}): "
                             "run make build (CMake target mocap_node) or set MOCAP_NODE_LIBRARY")


_lib: ctypes.CDLL | None = None


def library() -> ctypes.CDLL:
    """The loaded library with the streaming prototypes declared."""
    global _lib
    if _lib is None:
        path = library_path()
        lib = ctypes.CDLL(str(path))
        try:
            lib.imu_filter_stream_state_size.restype = ctypes.c_size_t
            lib.imu_filter_batch_settings_size.restype = ctypes.c_size_t
            lib.imu_filter_stream_init.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_float]
            lib.imu_filter_stream_init.restype = ctypes.c_int
            lib.imu_filter_stream_update.argtypes = [ctypes.c_void_p, Floats3, Floats3, ctypes.c_void_p, Floats4]
            lib.imu_filter_stream_update.restype = ctypes.c_uint8
        except AttributeError as e:
            raise FilterLibraryError(f"{path}: no streaming entry points ({e}): rebuild it (make build)") from None
        _lib = lib
    return _lib


class OrientationFilter:
    """One filter: init with the settings and the sample period, then update once per sample."""

    def __init__(self, sample_period_s: float, settings: ctypes.Structure | None = None):
        lib = library()
        if settings is not None and ctypes.sizeof(settings) != lib.imu_filter_batch_settings_size():
            raise FilterLibraryError(f"settings of {ctypes.sizeof(settings)} bytes, the library's are "
                                     f"{lib.imu_filter_batch_settings_size()}")
        self._state = ctypes.create_string_buffer(lib.imu_filter_stream_state_size())
        self._update = lib.imu_filter_stream_update
        self._gyr, self._acc, self._mag, self._q = Floats3(), Floats3(), Floats3(), Floats4()
        settings_ptr = None if settings is None else ctypes.addressof(settings)
        if lib.imu_filter_stream_init(self._state, settings_ptr, float(sample_period_s)) != 0:
            raise ValueError(f"the filter refused its settings or the sample period {sample_period_s!r} s")

    def update(self, gyr_rads: Sequence[float], acc_mps2: Sequence[float],
               mag_ut: Sequence[float] | None = None) -> tuple[tuple[float, float, float, float], int]:
        """One sample (sensor frame; gyr rad/s, acc m/s², mag µT or None for 6D): the orientation
        w, x, y, z (sensor -> ENU; 6D: heading from the gyroscope) and the FLAG_* bits."""
        self._gyr[:], self._acc[:] = gyr_rads, acc_mps2
        mag = None
        if mag_ut is not None:
            self._mag[:] = mag_ut
            mag = ctypes.addressof(self._mag)
        flags = self._update(self._state, self._gyr, self._acc, mag, self._q)
        return (self._q[0], self._q[1], self._q[2], self._q[3]), int(flags)
