"""Read a Qualisys Track Manager camera calibration (`.qca.txt`, XML) into a rig, as Pose2Sim's
own conversion reads it (the calibration its demo trials ship: Pose2Sim's Calib_qualisys.toml
of the Balancing trial is this conversion of its Calib.qca.txt).

Each video camera (model "video" or "none"; marker cameras are left out) gives: its image from
`fov_video` (left..right, top..bottom, inclusive); focal lengths and principal point from
`intrinsic` in the sensor's subpixels (64 a pixel), the principal point from the field of
view's corner; the distortion coefficients divided by 64 as well, as Pose2Sim does; its pose
from `transform`: the camera's position (mm) and a rotation whose rows r1., r2., r3. turn
world vectors into Qualisys's camera frame, whose y and z are OpenCV's -y and -z (a half
turn about x). Cameras come in their serials' natural order and are named by them.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import numpy as np

from mocap import _core
from mocap.errors import InputError

MAX_FILE_BYTES = 1 << 20
SUBPIXELS = 64.0
HALF_TURN_X = np.diag([1.0, -1.0, -1.0])


def _float(element: ElementTree.Element, name: str) -> float:
    value = element.get(name)
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InputError(f"<{element.tag}>: attribute {name} is {value!r}, not a number") from None


def _child(camera: ElementTree.Element, tag: str) -> ElementTree.Element:
    found = camera.find(tag)
    if found is None:
        raise InputError(f"camera {camera.get('serial')!r}: no <{tag}>")
    return found


def _camera(element: ElementTree.Element) -> _core.Camera:
    fov, intrinsic, transform = (_child(element, t) for t in ("fov_video", "intrinsic", "transform"))
    cam = _core.Camera()
    cam.name = str(element.get("serial"))
    left, top = _float(fov, "left"), _float(fov, "top")
    cam.width = int(round(_float(fov, "right") - left + 1))
    cam.height = int(round(_float(fov, "bottom") - top + 1))
    cam.fx = _float(intrinsic, "focalLengthU") / SUBPIXELS
    cam.fy = _float(intrinsic, "focalLengthV") / SUBPIXELS
    cam.cx = _float(intrinsic, "centerPointU") / SUBPIXELS - left
    cam.cy = _float(intrinsic, "centerPointV") / SUBPIXELS - top
    cam.distortion = [_float(intrinsic, n) / SUBPIXELS for n in
                      ("radialDistortion1", "radialDistortion2", "tangentalDistortion1", "tangentalDistortion2")] + [0.0]
    rows = np.array([[_float(transform, f"r{i}{j}") for j in (1, 2, 3)] for i in (1, 2, 3)])
    centre = np.array([_float(transform, a) for a in "xyz"]) / 1000.0
    cam.rotation = HALF_TURN_X @ rows
    cam.translation = -(HALF_TURN_X @ rows) @ centre
    return cam


def _natural(name: str) -> list:
    return [int(p) if p.isdigit() else p for p in re.split(r"(\d+)", name)]


def load(path: str | Path) -> _core.Rig:
    """The video cameras of a .qca.txt; InputError naming the file and the fault."""
    path = Path(path)
    try:
        if not path.is_file() or path.stat().st_size > MAX_FILE_BYTES:
            raise InputError(f"not a regular file of at most {MAX_FILE_BYTES >> 10} KiB")
        root = ElementTree.fromstring(path.read_bytes())
        cameras = [c for c in root.findall("cameras/camera")
                   if any(m in c.get("model", "").lower() for m in ("video", "none"))]
        if not cameras:
            raise InputError("no video camera (model \"video\" or \"none\")")
        rig = _core.Rig(sorted((_camera(c) for c in cameras), key=lambda c: _natural(c.name)))
        return _core.Rig.from_json(rig.to_json())  # every camera validated (mocap/camera.h)
    except InputError as e:
        raise InputError(f"{path}: {e}") from None
    except (OSError, ElementTree.ParseError, ValueError) as e:
        raise InputError(f"{path}: not a Qualisys calibration ({e})") from None
