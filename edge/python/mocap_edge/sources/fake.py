"""An in-process camera for tests of the camera box: `count` synthetic frames at `fps`
from `start_ns`, the same for the same options. Frame k shows a grey gradient with a
red square whose left edge is at x = (step * k) mod (width - square), so a test can
tell frames apart and check their order and colour channels."""

from __future__ import annotations

import numpy as np

from mocap_edge.errors import SourceError
from mocap_edge.sources.base import Frame, FrameSource

SQUARE = 16  # pixels


class FakeSource(FrameSource):
    def __init__(self, name: str = "", width: int = 320, height: int = 240, fps: float = 60.0,
                 count: int = 60, start_ns: int = 0, step: int = 4) -> None:
        if width <= SQUARE or height <= SQUARE or fps <= 0 or count < 0:
            raise SourceError(f"fake: need width, height > {SQUARE}, fps > 0, count >= 0")
        super().__init__((width, height), float(fps))
        self._count, self._start_ns, self._step, self._index = count, start_ns, step, 0
        self._background = np.repeat(np.linspace(0, 127, width, dtype=np.uint8)[None, :, None], 3, axis=2)
        self._background = np.repeat(self._background, height, axis=0)

    def square_x(self, index: int) -> int:
        return (self._step * index) % (self.size[0] - SQUARE)

    def _next_frame(self) -> Frame | None:
        if self._index >= self._count:
            return None
        index, self._index = self._index, self._index + 1
        image = self._background.copy()
        x, y = self.square_x(index), (self.size[1] - SQUARE) // 2
        image[y:y + SQUARE, x:x + SQUARE] = (255, 0, 0)
        return Frame(image, index, self._start_ns + round(index * 1e9 / self.nominal_fps))
