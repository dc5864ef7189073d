"""A V4L2 camera (USB / UVC, or any /dev/videoN) through OpenCV's V4L2 backend.

Capture time = CLOCK_REALTIME read when `grab()` returns, minus `latency_ns`. That instant
is later than the exposure mid-point by half the exposure, the sensor readout, the
transfer (USB) and the wait until this process runs: several ms to tens of ms, varying
from frame to frame by the scheduling delay (sub-ms on an idle box, more under load), and
by whole frame periods if frames queue up in the driver's buffers because the box reads
slower than the camera delivers. `latency_ns` removes the constant part once measured.
The driver's own buffer timestamp (CLOCK_MONOTONIC, at start or end of frame; OpenCV
reports it as CAP_PROP_POS_MSEC) has no scheduling error, but its instant is driver-
specific; with a trigger line (mocap_edge.trigger) the frame takes the edge's time anyway.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

from mocap_edge.errors import SourceError
from mocap_edge.sources.base import Frame, FrameSource, bgr_to_rgb, require_module
from mocap_edge.sources.files import OPENCV_HINT

log = logging.getLogger(__name__)


class V4l2Source(FrameSource):
    def __init__(self, device: str, width: int | None = None, height: int | None = None,
                 fps: float | None = None, latency_ns: int = 0) -> None:
        cv2 = require_module("cv2", "v4l2", OPENCV_HINT)
        if not Path(device).exists():
            raise SourceError(f"v4l2: no camera device at {device} (ls /dev/video* lists the cameras here)")
        self._capture = cv2.VideoCapture(device, cv2.CAP_V4L2)
        if not self._capture.isOpened():
            raise SourceError(f"v4l2: cannot open {device} for capture (busy, no permission, or not a camera)")
        for prop, value in ((cv2.CAP_PROP_FRAME_WIDTH, width), (cv2.CAP_PROP_FRAME_HEIGHT, height),
                            (cv2.CAP_PROP_FPS, fps)):
            if value is not None and not self._capture.set(prop, value):
                log.warning("v4l2: %s refused setting %d to %s", device, prop, value)
        get = self._capture.get
        super().__init__((int(get(cv2.CAP_PROP_FRAME_WIDTH)), int(get(cv2.CAP_PROP_FRAME_HEIGHT))),
                         float(get(cv2.CAP_PROP_FPS)))
        self._device, self._latency_ns, self._index = device, latency_ns, 0

    def _next_frame(self) -> Frame | None:
        while True:
            if not self._capture.grab():
                log.warning("v4l2: %s stopped delivering frames", self._device)
                return None
            grabbed_ns = time.time_ns()
            index, self._index = self._index, self._index + 1
            ok, bgr = self._capture.retrieve()
            if ok:
                return Frame(bgr_to_rgb(bgr), index, grabbed_ns - self._latency_ns)
            self.dropped += 1

    def _release(self) -> None:
        self._capture.release()
