"""A Raspberry Pi camera (CSI) through libcamera's picamera2, `libcamera:N` for camera N.

Timestamps come from each request's metadata, not from when Python got the frame:
- `SensorTimestamp` (ns) is documented by libcamera as the start of exposure of the first
  row on CLOCK_BOOTTIME (control_ids_core.yaml), but on Raspberry Pi it is the frame-start
  interrupt of the CSI receiver, i.e. when the first row has finished exposing (picamera2
  issue #821), on CLOCK_MONOTONIC (libcamera bug 254, cited in camera_ros PR #127); the two
  clocks differ only by time spent suspended, which a camera box never is.
- so the first row's exposure mid-point is SensorTimestamp - ExposureTime / 2 (ExposureTime
  in us), moved to CLOCK_REALTIME by the offset measured for each frame
  (mocap_edge.clocks). Later rows of a rolling shutter are later by their readout time.
picamera2 ships with Raspberry Pi OS (apt python3-picamera2) and cannot be installed on
other machines; opening this source there raises SourceError naming the module.
"""

from __future__ import annotations

import time

import numpy as np

from mocap_edge.clocks import realtime_offset_ns
from mocap_edge.errors import SourceError
from mocap_edge.sources.base import Frame, FrameSource, require_module

PICAMERA2_HINT = ("Raspberry Pi OS: apt install python3-picamera2, and make the venv with "
                  "--system-site-packages")


def mid_exposure_ns(sensor_timestamp_ns: int, exposure_us: int | None) -> int:
    """The first row's exposure mid-point on the shared timebase (CLOCK_REALTIME) from a
    request's SensorTimestamp (CLOCK_MONOTONIC) and ExposureTime (us; None: unknown, 0)."""
    return sensor_timestamp_ns - (exposure_us or 0) * 500 + realtime_offset_ns(time.CLOCK_MONOTONIC)


class LibcameraSource(FrameSource):
    def __init__(self, camera: str, width: int = 1280, height: int = 720, fps: float = 60.0,
                 buffer_count: int = 4) -> None:
        picamera2 = require_module("picamera2", "libcamera", PICAMERA2_HINT)
        if not camera.isdigit():
            raise SourceError(f"libcamera: expected a camera number (libcamera:0), got {camera!r}")
        try:
            self._camera = picamera2.Picamera2(int(camera))
        except (IndexError, RuntimeError) as e:
            raise SourceError(f"libcamera: cannot open camera {camera} ({e}); rpicam-hello --list-cameras "
                              "lists them") from None
        frame_us = round(1e6 / fps)
        # libcamera names formats by the 32-bit word: "BGR888" puts R, G, B in memory order
        config = self._camera.create_video_configuration(
            main={"size": (width, height), "format": "BGR888"}, buffer_count=buffer_count,
            controls={"FrameDurationLimits": (frame_us, frame_us)})
        self._camera.configure(config)
        self._camera.start()
        super().__init__((width, height), float(fps))
        self._index = 0

    def _next_frame(self) -> Frame | None:
        while True:
            request = self._camera.capture_request()
            try:
                image = request.make_array("main")
                metadata = request.get_metadata()
            finally:
                request.release()  # buffers go back to libcamera at once
            index, self._index = self._index, self._index + 1
            if "SensorTimestamp" in metadata:
                return Frame(np.ascontiguousarray(image[:, :, :3]), index,
                             mid_exposure_ns(metadata["SensorTimestamp"], metadata.get("ExposureTime")))
            self.dropped += 1

    def _release(self) -> None:
        self._camera.stop()
        self._camera.close()
