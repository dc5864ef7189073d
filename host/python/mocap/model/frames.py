"""The studio's messages turned into the frames mocapd would solve, by mocapd's own input
path (C++ InputPath through the bindings: each message checked and mapped to the session's
cameras and IMUs, the subject chosen per camera, camera frames grouped by capture time and
the IMUs interpolated to the frame times, late input dropped by its arrival time). The
calibration (from a recording or from the live calibrator's last seconds) reads these
frames, so it calibrates on what the live host solves with.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import numpy as np

from mocap import _core
from mocap.errors import InputError
from mocap.net import wire

INPUT_TYPES = ("mocap.v1.KeypointFrame", "mocap.v1.ImuBatch")


def input_path(session: Path) -> _core.InputPath:
    """A fresh InputPath for `session` (its rig, layout, IMU set, "sync" settings and the
    solver's min_confidence, read as mocapd reads them); InputError when mocapd would refuse it."""
    try:
        return _core.InputPath.from_session(str(session))
    except ValueError as e:
        raise InputError(str(e)) from None


def synchronise(path: _core.InputPath, messages: Iterable[tuple[int, str, bytes]]) -> list:
    """The synchronised frames (_core.SyncedFrame, oldest first) of (arrival ns, type name,
    payload) messages in arrival order; the end of the messages is the end of the input (what
    is pending is released). Messages other than camera frames and IMU batches are skipped;
    what the path drops is counted in path.dropped."""
    frames = []
    for arrival_ns, type_name, payload in messages:
        if type_name not in INPUT_TYPES:
            continue
        path.feed(type_name, payload, arrival_ns)
        frames += path.take_ready(arrival_ns)
    return frames + path.flush()


def synchronise_all(path: _core.InputPath, messages: Iterable[tuple[int, str, bytes]],
                    times_ns: list[int]) -> list:
    """synchronise() of messages that have no late or lost input (a simulated or offline
    studio): RuntimeError unless the path released exactly the frames at times_ns and dropped
    nothing — anything else is a fault of whoever made the messages, or of the path."""
    frames = synchronise(path, messages)
    if [f.time_ns for f in frames] != list(times_ns) or path.dropped:
        raise RuntimeError(f"the input path delivered {len(frames)} of {len(times_ns)} frames "
                           f"(dropped: {dict(path.dropped)})")
    return frames


def camera_frame(camera: _core.Camera, index: int, time_ns: int, layout: str,
                 persons: Iterable[np.ndarray] | None) -> wire.KeypointFrame:
    """The KeypointFrame a camera box sends for frame `index` captured (and sent) at time_ns:
    persons (K, 3) x, y (px), confidence, or None when the detector did not run on it (HS)."""
    msg = wire.KeypointFrame(camera_id=camera.name, frame_index=index, capture_time_ns=time_ns,
                             image_width=camera.width, image_height=camera.height, keypoint_layout=layout,
                             detected=persons is not None, send_time_ns=time_ns)
    for p in persons or []:
        msg.persons.add(x=p[:, 0].tolist(), y=p[:, 1].tolist(), confidence=p[:, 2].tolist(), score=1.0)
    return msg
