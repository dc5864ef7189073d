"""A simulated camera, `sim:STREAMS`: one camera of the simulated studio's stream file
(mocap_edge.streams) played as if it were capturing now — python-can's `virtual`
interface, for the camera box.

Frame f is captured at start_ns + the file's frame time (the simulated capture jitter
included) and delivered at that time, not before, as a live camera delivers it. Its
picture is flat and its colour codes f (`picture`), a read-only view of one pixel with the
camera's image size: the `sim` keypoint model (detect/sim.py) reads f back and answers with
the file's keypoints of that frame, so the box's own loop — tracking, high-speed mode,
trigger pairing, publishing — runs on the simulated studio.
"""

from __future__ import annotations

import functools
import math
import time
import zipfile
from pathlib import Path

import numpy as np

from mocap_edge import pacing
from mocap_edge.errors import SourceError
from mocap_edge.sources.base import Frame, FrameSource
from mocap_edge.streams import CAMERA_FIELDS, CameraStream, Streams

MAX_FRAMES = 1 << 24  # frame numbers a picture's 24 bits of colour can code
# A live source opened during the take skips the frames older than this (what a camera's
# driver queue would still hold is delivered).
LIVE_BACKLOG_NS = 100_000_000


def picture(index: int, size: tuple[int, int]) -> np.ndarray:
    """A flat (H, W, 3) uint8 picture of size (W, H) whose colour R, G, B codes `index`."""
    if not 0 <= index < MAX_FRAMES:
        raise ValueError(f"a simulated picture codes frames 0 to {MAX_FRAMES - 1}, not {index}")
    code = np.array([index >> 16 & 255, index >> 8 & 255, index & 255], np.uint8)
    return np.broadcast_to(code, (size[1], size[0], 3))


def frame_of(image: np.ndarray) -> int:
    """The frame number a simulated picture codes."""
    r, g, b = (int(v) for v in image[0, 0])
    return r << 16 | g << 8 | b


def load_camera(streams: str, camera: str) -> CameraStream:
    """One camera of a stream file (read once per process while the file is unchanged: the
    box's source and detector share it, read-only); raises ValueError or OSError naming what
    is wrong."""
    stat = Path(streams).stat()
    return _load_camera(streams, camera, stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=4)
def _load_camera(streams: str, camera: str, _mtime_ns: int, _size: int) -> CameraStream:
    try:
        studio = Streams.load(Path(streams), read=CAMERA_FIELDS)
    except (KeyError, TypeError, ValueError, zipfile.BadZipFile) as e:
        raise ValueError(f"{streams} is not a stream file ({e})") from None
    stream = studio.camera(camera)
    for shared in (stream.frame_times_ns, stream.keypoints, stream.detected):
        shared.flags.writeable = False
    return stream


class SimulatedSource(FrameSource):
    """Camera `camera` of the stream file `streams`, captured from `start_ns` (default now).
    `span` (from_s, to_s): only the frames of that span of the take (a box switched on late
    or off early; default all); their numbers are the file's. live: the frames whose time
    has passed at the first read are not captured (a camera started, or started again,
    during the take captures from then on); otherwise they are delivered at once (offline).
    clock_steps [(at_s, offset_s), ...]: from take time at_s on, the box's clock reads offset_s
    off the shared timebase (a PTP loss; 0 when it locks again): the frames are captured at
    their time and stamped with the box's clock."""

    def __init__(self, streams: str, camera: str, start_ns: int | None = None,
                 span: tuple[float, float] = (-math.inf, math.inf), live: bool = False,
                 clock_steps: tuple[tuple[float, float], ...] = ()) -> None:
        try:
            self.stream = load_camera(streams, camera)
        except (OSError, ValueError) as e:
            raise SourceError(f"sim: {e}") from None
        times = self.stream.frame_times_ns
        if len(times) > MAX_FRAMES:
            raise SourceError(f"sim: {len(times)} frames, more than a picture codes ({MAX_FRAMES})")
        super().__init__(self.stream.image_size, 1e9 / float(np.median(np.diff(times))) if len(times) > 1 else 60.0)
        self._start_ns = time.time_ns() if start_ns is None else start_ns
        seconds = times * 1e-9
        self._frames = iter(np.flatnonzero((seconds >= span[0]) & (seconds < span[1])).tolist())
        self._oldest_ns = time.time_ns() - LIVE_BACKLOG_NS if live else None
        steps = sorted(clock_steps)
        self._step_at_ns = np.array([self._start_ns + round(at * 1e9) for at, _ in steps], np.int64)
        self._step_offset_ns = np.array([0, *(round(offset * 1e9) for _, offset in steps)], np.int64)

    def _next_frame(self) -> Frame | None:
        f = next(self._frames, None)
        if self._oldest_ns is not None:  # once: what was captured before the camera was opened is gone
            while f is not None and self._start_ns + int(self.stream.frame_times_ns[f]) < self._oldest_ns:
                f = next(self._frames, None)
            self._oldest_ns = None
        if f is None:
            return None
        capture_ns = self._start_ns + int(self.stream.frame_times_ns[f])
        pacing.sleep_until(capture_ns)
        return Frame(picture(f, self.size), f, capture_ns + self.clock_offset_ns(capture_ns))

    def clock_offset_ns(self, t_ns: int) -> int:
        """How far the box's clock reads off the shared timebase at t_ns (clock_steps)."""
        return int(self._step_offset_ns[np.searchsorted(self._step_at_ns, t_ns, side="right")])
