"""What the page draws that does not change during a take: the skeleton's bones (a joint to its
parent's) and each camera of the rig as a frustum. World frame: ours (right-handed, Z up,
metres)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from mocap import _core, paths
from mocap.errors import InputError
from mocap.io.session import Session

FRUSTUM_DEPTH_M = 0.4  # how far each camera's drawn pyramid reaches


def bones(skeleton_file: Path) -> list[dict[str, Any]]:
    """[{"name", "parent"}] of a skeleton file (mocap.skeleton/1), in its bone order."""
    try:
        data = json.loads(Path(skeleton_file).read_text())
        return [{"name": str(b["name"]), "parent": b.get("parent")} for b in data["bones"]]
    except (ValueError, KeyError, TypeError) as e:
        raise InputError(f"{skeleton_file}: not a skeleton file ({e})") from None


def frustum(camera: _core.Camera, depth: float = FRUSTUM_DEPTH_M) -> dict[str, Any]:
    """A rig camera as its centre and the four image corners' rays (without distortion) cut at
    `depth` along its optical axis."""
    r = np.asarray(camera.rotation, dtype=float)  # world -> camera
    centre = np.asarray(camera.center(), dtype=float)
    corners = [centre + depth * (r.T @ np.array([(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0]))
               for u, v in ((0, 0), (camera.width, 0), (camera.width, camera.height), (0, camera.height))]
    return {"name": camera.name, "centre": centre.round(4).tolist(), "corners": [c.round(4).tolist() for c in corners]}


def scene(session_file: Path | None) -> dict[str, Any]:
    """The page's "scene" message: the session's bones and cameras; without a session, the
    default skeleton's bones and no cameras."""
    if session_file is None:
        return {"type": "scene", "bones": bones(paths.DEFAULT_SKELETON), "cameras": []}
    session = Session.load(session_file)
    cameras = [frustum(c) for c in _core.Rig.load(str(session.file("rig"))).cameras]
    return {"type": "scene", "bones": bones(session.file("skeleton")), "cameras": cameras}
