"""Read the Pose2Sim / anipose `Calib.toml` camera layout into a rig.

Each camera is a table with `size` [w, h] (px), `matrix` (OpenCV K), `distortions`
[k1, k2, p1, p2] (k3 optional as a fifth value), `rotation` (Rodrigues vector, world ->
camera) and `translation` (metres, world -> camera); a `[metadata]` table is ignored.
Fisheye cameras are refused: the solver models OpenCV's pinhole distortion only.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np

from mocap import _core, rotations
from mocap.errors import InputError

MAX_FILE_BYTES = 1 << 20  # a Calib.toml (a few hundred bytes a camera)
MAX_IMAGE_SIDE = 1 << 16  # pixels


def _camera(key: str, table: dict) -> _core.Camera:
    try:
        k = np.asarray(table["matrix"], dtype=float)
        size = [int(round(v)) for v in table["size"]]
        dist = [float(v) for v in table["distortions"]]
        rvec = np.asarray(table["rotation"], dtype=float)
        tvec = np.asarray(table["translation"], dtype=float)
    except (KeyError, TypeError, ValueError, OverflowError) as e:
        raise InputError(f"camera [{key}]: missing or malformed field ({e})") from None
    if not all(0 < v <= MAX_IMAGE_SIDE for v in size):
        raise InputError(f"camera [{key}]: size {size} is not 1..{MAX_IMAGE_SIDE} pixels a side")
    if table.get("fisheye", False):
        raise InputError(f"camera [{key}]: fisheye cameras are not supported")
    if k.shape != (3, 3) or rvec.shape != (3,) or tvec.shape != (3,) or len(dist) not in (4, 5) or len(size) != 2:
        raise InputError(f"camera [{key}]: wrong array sizes")
    cam = _core.Camera()
    cam.name = str(table.get("name", key))
    cam.width, cam.height = size
    cam.fx, cam.fy, cam.cx, cam.cy = k[0, 0], k[1, 1], k[0, 2], k[1, 2]
    cam.distortion = (dist + [0.0])[:5]
    cam.rotation = rotations.exp(rvec)
    cam.translation = tvec
    return cam


def read(path: str | Path) -> dict:
    """The TOML of `path`; InputError when it is not a regular file (a FIFO would block the
    read), too large, unreadable or not TOML."""
    try:
        if not Path(path).is_file():
            raise InputError(f"{path}: not found or not a regular file")
        if Path(path).stat().st_size > MAX_FILE_BYTES:
            raise InputError(f"{path}: larger than {MAX_FILE_BYTES >> 10} KiB")
        return tomllib.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise InputError(f"{path}: not a TOML file ({e})") from None


def load(path: str | Path) -> _core.Rig:
    data = read(path)
    cams = [_camera(key, t) for key, t in data.items() if key != "metadata" and isinstance(t, dict)]
    if not cams:
        raise InputError(f"{path}: no camera tables")
    names = [c.name for c in cams]
    twice = [n for i, n in enumerate(names) if n in names[:i]]
    if twice:  # which one a take means would be a guess
        raise InputError(f"{path}: two camera tables are named {twice[0]!r}")
    # Round-trip through the rig parser, which validates every camera (distortion included:
    # mocap/camera.h, Camera::IsValid).
    try:
        return _core.Rig.from_json(_core.Rig(cams).to_json())
    except ValueError as e:
        raise InputError(f"{path}: {e}") from None


def _floats(values) -> str:
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


def dumps(rig: _core.Rig) -> str:
    """The rig in the Pose2Sim layout (`[cam_01]`.. in rig order, `name` the camera's name;
    distortions k1 k2 p1 p2, and k3 only when it is not zero); `load` reads it back."""
    out = []
    for i, cam in enumerate(rig.cameras):
        dist = list(cam.distortion)
        matrix = [[cam.fx, 0.0, cam.cx], [0.0, cam.fy, cam.cy], [0.0, 0.0, 1.0]]
        out.append(f"[cam_{i + 1:02d}]\nname = {json.dumps(cam.name)}\nsize = {_floats([cam.width, cam.height])}\n"
                   f"matrix = [{', '.join(_floats(r) for r in matrix)}]\n"
                   f"distortions = {_floats(dist if dist[4] else dist[:4])}\n"
                   f"rotation = {_floats(rotations.log(np.asarray(cam.rotation)))}\n"
                   f"translation = {_floats(cam.translation)}\nfisheye = false\n")
    return "\n".join(out) + "\n[metadata]\nadjusted = false\nerror = 0.0\n"
