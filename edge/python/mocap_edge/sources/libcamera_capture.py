"""`libcamera:N` (or `libcamera:ID`) through the project's own adapter over libcamera's C++ API
(edge/libcamera/capture.h, the extension `mocap_edge.sources._libcamera`), wherever
picamera2 (Raspberry Pi OS only) is absent: Debian, Yocto images, the VM tests' vimc camera.

Times as pi_camera.py explains: the first row's exposure mid-point is SensorTimestamp -
ExposureTime / 2, moved from CLOCK_MONOTONIC to CLOCK_REALTIME by the offset measured for
each frame. A frame's index is its sequence number counted from the first frame, so frames
the camera dropped leave gaps (and are counted in `dropped`).
"""

from __future__ import annotations

import importlib
import os

from mocap_edge.errors import SourceError
from mocap_edge.sources.base import Frame, FrameSource
from mocap_edge.sources.pi_camera import LibcameraSource, mid_exposure_ns

FRAME_TIMEOUT_S = 2.0  # a camera silent this long has stopped: an error, not the end of the take
NOT_BUILT_HINT = ("neither picamera2 (Raspberry Pi OS: apt install python3-picamera2) nor the project's "
                  "libcamera capture (built by `make build` where libcamera-dev is installed) is here")


def open_libcamera(camera: str, width: int = 1280, height: int = 720, fps: float = 60.0,
                   buffer_count: int = 4) -> FrameSource:
    """The `libcamera:` source: picamera2's where it is installed (a Raspberry Pi), else the
    project's adapter; SourceError when neither is available."""
    try:
        importlib.import_module("picamera2")
    except ImportError:
        return LibcameraCaptureSource(camera, width, height, fps, buffer_count)
    return LibcameraSource(camera, width, height, fps, buffer_count)


def _adapter():
    # libcamera logs at INFO from the moment it is loaded (its version, every camera opened):
    # a box's log keeps libcamera's warnings, unless LIBCAMERA_LOG_LEVELS asks for more.
    os.environ.setdefault("LIBCAMERA_LOG_LEVELS", "*:WARN")
    try:
        return importlib.import_module("mocap_edge.sources._libcamera")
    except ImportError as e:
        raise SourceError(f"libcamera: {NOT_BUILT_HINT} ({e})") from None


class LibcameraCaptureSource(FrameSource):
    def __init__(self, camera: str, width: int = 1280, height: int = 720, fps: float = 60.0,
                 buffer_count: int = 4) -> None:
        adapter = _adapter()
        if not camera:
            raise SourceError("libcamera: name a camera by index or id (libcamera:0)")
        try:
            self._capture = adapter.Capture(camera, width, height, float(fps), buffer_count)
        except adapter.CaptureError as e:
            raise SourceError(str(e)) from None
        self.camera_id = self._capture.id
        self.pixel_format = self._capture.pixel_format
        super().__init__(tuple(self._capture.size), float(fps))
        self._error = adapter.CaptureError
        self._first_sequence: int | None = None
        self._untimed = 0

    def _next_frame(self) -> Frame | None:
        while True:
            try:
                got = self._capture.next(FRAME_TIMEOUT_S)
            except self._error as e:
                raise SourceError(str(e)) from None
            if got is None:
                raise SourceError(f"libcamera: camera {self.camera_id} delivered no frame in {FRAME_TIMEOUT_S} s")
            image, sequence, sensor_ns, exposure_us = got
            self._first_sequence = sequence if self._first_sequence is None else self._first_sequence
            self._untimed += sensor_ns is None
            # what the camera dropped (sequence gaps, failed requests) and frames without a time
            self.dropped = self._capture.dropped + self._capture.failed + self._untimed
            if sensor_ns is None:
                continue
            return Frame(image, sequence - self._first_sequence, mid_exposure_ns(sensor_ns, exposure_us))

    def _release(self) -> None:
        self._capture.close()
