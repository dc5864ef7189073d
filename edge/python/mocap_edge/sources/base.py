"""Frames, the frame-source interface and the registry of backends.

A source is opened by URI, `open_source("video:take.mp4", start_ns=...)`; the scheme picks
the backend and the options go to its constructor. Capture times are int64 ns on the
shared timebase (CLOCK_REALTIME, PTP-disciplined in a studio), the exposure mid-point as
in mocap.v1 KeypointFrame; each backend says how close it gets.
"""

from __future__ import annotations

import abc
import dataclasses
import importlib
from collections.abc import Iterator
from types import ModuleType, TracebackType

import numpy as np

from mocap_edge import registry
from mocap_edge.errors import SourceError

# scheme -> "module:class"; imported only when opened, so a box needs only its backend's modules
BACKENDS: dict[str, str] = {
    "video": "mocap_edge.sources.files:VideoFileSource",
    "images": "mocap_edge.sources.files:ImageFolderSource",
    "v4l2": "mocap_edge.sources.v4l2:V4l2Source",
    "libcamera": "mocap_edge.sources.libcamera_capture:open_libcamera",
    "fake": "mocap_edge.sources.fake:FakeSource",
    "sim": "mocap_edge.sources.sim:SimulatedSource",
}


@dataclasses.dataclass(frozen=True)
class Frame:
    image: np.ndarray  # (H, W, 3) uint8, R, G, B
    index: int  # frame number from the source's start; the trigger count once paired
    capture_time_ns: int  # exposure mid-point, ns on the shared timebase


class FrameSource(abc.ABC):
    """An iterable of Frames in capture order. Backends fill in `_next_frame` (and
    `_release` if they hold a device); iteration ends at the end of the source or on close.
    `dropped` counts frames the backend read but could not use (undecodable, bad time)."""

    def __init__(self, size: tuple[int, int], nominal_fps: float) -> None:
        self.size = size  # (width, height), pixels
        self.nominal_fps = nominal_fps
        self.dropped = 0
        self._closed = False

    @abc.abstractmethod
    def _next_frame(self) -> Frame | None:
        """The next frame, or None at the end of the source."""

    def _release(self) -> None:
        """Frees the backend's device or file."""

    def __iter__(self) -> Iterator[Frame]:
        while not self._closed:
            frame = self._next_frame()
            if frame is None:
                return
            yield frame

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._release()

    def __enter__(self) -> FrameSource:
        return self

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.close()


def open_source(uri: str, **options: object) -> FrameSource:
    """Opens `scheme:location` (video:PATH, images:DIR, v4l2:/dev/videoN, libcamera:N,
    fake:, sim:STREAMS) with the backend's keyword options; raises SourceError with the reason."""
    scheme, colon, _ = uri.partition(":")
    if not colon or scheme not in BACKENDS:
        raise SourceError(f"unknown frame source {uri!r}: the URI must start with one of {registry.known(BACKENDS)}")
    return registry.open_backend(BACKENDS, uri, SourceError, "source", **options)


def require_module(name: str, scheme: str, hint: str) -> ModuleType:
    """Imports a backend's third-party module, or raises SourceError naming it."""
    try:
        return importlib.import_module(name)
    except ImportError:
        raise SourceError(f"{scheme}: sources need the Python module '{name}', which is not installed "
                          f"here ({hint})") from None


def bgr_to_rgb(image: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(image[:, :, ::-1])
