"""A rig calibration's input from a recording of the camera boxes' streams (`mocap record`):
each camera's KeypointFrames put on common frames by their capture times (the boxes are
triggered together: a frame's captures agree within a fraction of its interval), and the
intrinsics each camera needs, from a Calib.toml, the recording's attached session, or the
image size and a field of view."""

from __future__ import annotations

import dataclasses
import math
import tempfile
from pathlib import Path

import numpy as np

from mocap import _core
from mocap.errors import InputError
from mocap.io import calib_toml
from mocap.io.session import Session
from mocap.io.take_folder import KEYPOINTS
from mocap.net import wire
from mocap.recording import reader

CAMERA_TOPIC = "/camera/"


@dataclasses.dataclass
class Detections:
    cameras: list[str]  # the camera ids, sorted
    sizes: dict[str, tuple[int, int]]  # image width, height per camera
    layout: str
    rate: float  # frames per second
    people: list[list[np.ndarray]]  # [camera][frame]: (P, K, 3) x, y, confidence
    session_rig: _core.Rig | None  # the attached session's, if any


def read(path: Path, with_session: bool = True) -> Detections:
    """Every camera's detections of recording `path` on common frames and, with_session, the
    rig of its attached session (for its intrinsics, or to compare with); InputError when it
    has no camera frames, or frames of several keypoint layouts."""
    by_camera: dict[str, list[wire.KeypointFrame]] = {}
    with reader.Recording(path) as recording:
        for message in recording.messages():
            if message.topic.startswith(CAMERA_TOPIC):
                try:
                    frame = wire.decode([message.type_name.encode(), message.payload])
                except wire.WireError:
                    continue  # counted when recorded
                if isinstance(frame, wire.KeypointFrame) and frame.detected:
                    by_camera.setdefault(frame.camera_id, []).append(frame)
        session_rig = _session_rig(recording) if with_session else None
    if not by_camera:
        raise InputError(f"{path}: no camera frames with detections ({CAMERA_TOPIC}*) in this recording")
    layouts = {f.keypoint_layout for frames in by_camera.values() for f in frames}
    if len(layouts) != 1:
        raise InputError(f"{path}: the cameras' frames are of several keypoint layouts ({', '.join(sorted(layouts))})")
    cameras, layout = sorted(by_camera), layouts.pop()
    if layout not in KEYPOINTS:
        raise InputError(f"{path}: keypoint layout {layout!r} is not one of {', '.join(KEYPOINTS)}")
    times, rate = common_frames(by_camera)
    people = [on_frames(by_camera[c], times, 0.5e9 / rate, KEYPOINTS[layout]) for c in cameras]
    sizes = {c: (by_camera[c][0].image_width, by_camera[c][0].image_height) for c in cameras}
    return Detections(cameras, sizes, layout, rate, people, session_rig)


def _session_rig(recording: reader.Recording) -> _core.Rig | None:
    with tempfile.TemporaryDirectory() as folder:
        found = recording.session(folder)
        return None if found is None else _core.Rig.load(str(Session.load(found).file("rig")))


def common_frames(by_camera: dict[str, list]) -> tuple[np.ndarray, float]:
    """The frames' capture times (those of the camera with the most frames) and the frame rate."""
    reference = max(by_camera.values(), key=len)
    times = np.unique([f.capture_time_ns for f in reference])
    if len(times) < 2:
        raise InputError("fewer than two frames of any camera: no frame rate, nothing to calibrate from")
    return times, float(1e9 / np.median(np.diff(times)))


def on_frames(frames: list, times: np.ndarray, within_ns: float, keypoints: int) -> list[np.ndarray]:
    """Per common frame, the camera's persons (P, K, 3) captured nearest its time (within_ns;
    none when it has no capture that near); a person of another keypoint count is left out."""
    own = np.array([f.capture_time_ns for f in frames])
    order = np.argsort(own, kind="stable")
    own, frames = own[order], [frames[i] for i in order]
    out = []
    for t in times:
        i = int(np.searchsorted(own, t))
        near = [j for j in (i - 1, i) if 0 <= j < len(own) and abs(own[j] - t) <= within_ns]
        persons = frames[min(near, key=lambda j: abs(own[j] - t))].persons if near else []
        kept = [np.stack([p.x, p.y, p.confidence], axis=1) for p in persons if len(p.x) == keypoints]
        out.append(np.array(kept, dtype=float).reshape(len(kept), keypoints, 3))
    return out


def intrinsics(detections: Detections, given: str | None, fov_deg: float | None) -> list[_core.Camera]:
    """Each camera's intrinsics: from the Calib.toml `given` (by camera name), else from the
    recording's session, else a pinhole of horizontal field of view fov_deg on the image."""
    if given is not None:
        known = {cam.name: cam for cam in calib_toml.load(given).cameras}
        source = given
    elif fov_deg is None and detections.session_rig is not None:
        known = {cam.name: cam for cam in detections.session_rig.cameras}
        source = "the recording's session"
    elif fov_deg is not None:
        return [from_field_of_view(c, *detections.sizes[c], fov_deg) for c in detections.cameras]
    else:
        raise InputError("no intrinsics: give --intrinsics Calib.toml or --fov DEG (the recording has no session)")
    missing = [c for c in detections.cameras if c not in known]
    if missing:
        raise InputError(f"{source}: no camera named {missing[0]!r} (the recording's cameras: "
                         f"{', '.join(detections.cameras)})")
    return [known[c] for c in detections.cameras]


def from_field_of_view(name: str, width: int, height: int, fov_deg: float) -> _core.Camera:
    """A pinhole camera without distortion whose image `width` pixels wide spans fov_deg
    horizontally, its principal point at the image's centre."""
    if not 10.0 <= fov_deg <= 170.0:
        raise InputError(f"a horizontal field of view of {fov_deg} degrees: give 10-170")
    if width <= 0 or height <= 0:
        raise InputError(f"camera {name}: its frames do not say the image size; give --intrinsics")
    camera = _core.Camera()
    camera.name, camera.width, camera.height = name, width, height
    camera.fx = camera.fy = (width / 2.0) / math.tan(math.radians(fov_deg) / 2.0)
    camera.cx, camera.cy = width / 2.0, height / 2.0
    return camera
