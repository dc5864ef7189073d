"""Recorded footage: a video file, or a folder of images, played as if captured from
`start_ns` on the shared timebase (default: when opened)."""

from __future__ import annotations

import logging
import time
from pathlib import Path

import numpy as np

from mocap_edge.errors import SourceError
from mocap_edge.sources.base import Frame, FrameSource, bgr_to_rgb, require_module

log = logging.getLogger(__name__)
OPENCV_HINT = "pip install opencv-python-headless, pinned in requirements.txt"
IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp"}


class VideoFileSource(FrameSource):
    """Capture time = start_ns + the frame's presentation timestamp in the container (as
    OpenCV's FFmpeg backend reports it after each read), so variable frame rates and gaps
    keep their real times. A frame whose time does not advance is dropped and counted."""

    def __init__(self, path: str, start_ns: int | None = None) -> None:
        self._cv2 = require_module("cv2", "video", OPENCV_HINT)
        if not Path(path).is_file():
            raise SourceError(f"video: no such file: {path}")
        self._capture = self._cv2.VideoCapture(path, self._cv2.CAP_FFMPEG)
        if not self._capture.isOpened():
            raise SourceError(f"video: cannot decode {path} (not a video OpenCV's FFmpeg can read)")
        get = self._capture.get
        super().__init__((int(get(self._cv2.CAP_PROP_FRAME_WIDTH)), int(get(self._cv2.CAP_PROP_FRAME_HEIGHT))),
                         float(get(self._cv2.CAP_PROP_FPS)))
        self._start_ns = time.time_ns() if start_ns is None else start_ns
        self._index = 0
        self._last_pts_ns = -1

    def _next_frame(self) -> Frame | None:
        while True:
            ok, bgr = self._capture.read()
            if not ok:
                return None
            pts_ns = round(self._capture.get(self._cv2.CAP_PROP_POS_MSEC) * 1e6)
            index, self._index = self._index, self._index + 1
            if pts_ns > self._last_pts_ns:
                self._last_pts_ns = pts_ns
                return Frame(bgr_to_rgb(bgr), index, self._start_ns + pts_ns)
            self.dropped += 1
            log.warning("video: frame %d has no later timestamp than the one before (%d ns): dropped", index, pts_ns)

    def _release(self) -> None:
        self._capture.release()


class ImageFolderSource(FrameSource):
    """The images of a folder in name order, frame k captured at start_ns + k / fps. All
    must have the first one's size; an unreadable or differently sized one is dropped and
    counted (its index and time are skipped, not reused)."""

    def __init__(self, folder: str, fps: float, start_ns: int | None = None) -> None:
        self._cv2 = require_module("cv2", "images", OPENCV_HINT)
        if not Path(folder).is_dir():
            raise SourceError(f"images: no such folder: {folder}")
        if fps <= 0:
            raise SourceError(f"images: fps must be positive, got {fps}")
        self._paths = sorted(p for p in Path(folder).iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
        if not self._paths:
            raise SourceError(f"images: no images ({', '.join(sorted(IMAGE_SUFFIXES))}) in {folder}")
        first = self._read(self._paths[0])
        if first is None:
            raise SourceError(f"images: cannot read the first image, {self._paths[0]}")
        super().__init__((first.shape[1], first.shape[0]), float(fps))
        self._start_ns = time.time_ns() if start_ns is None else start_ns
        self._index = 0

    def _read(self, path: Path) -> np.ndarray | None:
        bgr = self._cv2.imread(str(path), self._cv2.IMREAD_COLOR)
        return None if bgr is None else bgr_to_rgb(bgr)

    def _next_frame(self) -> Frame | None:
        while self._index < len(self._paths):
            index, self._index = self._index, self._index + 1
            image = self._read(self._paths[index])
            if image is not None and (image.shape[1], image.shape[0]) == self.size:
                return Frame(image, index, self._start_ns + round(index * 1e9 / self.nominal_fps))
            self.dropped += 1
            log.warning("images: %s is unreadable or not %dx%d: dropped", self._paths[index], *self.size)
        return None
