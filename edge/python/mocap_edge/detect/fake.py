"""An in-process keypoint model for tests, `fake:`: a person is a pure red (255, 0, 0)
square, as the fake: camera draws one. Every keypoint of the layout sits at the square's
centre with confidence 1; the next region is the square's, doubled, so a square that moves
a few pixels a frame is tracked and one that jumps is lost (presence 0) and found again by
`detect`. Deterministic, no model files."""

from __future__ import annotations

import numpy as np

from mocap_edge.detect import layouts
from mocap_edge.detect.base import Crop, Detector, Person
from mocap_edge.detect.roi import Roi

PADDING = 2.0  # region side / square side


class FakeDetector(Detector):
    """presence: what a person found in its region reports (below min_presence: dropped)."""

    def __init__(self, location: str = "", layout: str = "blazepose33", presence: float = 1.0,
                 min_presence: float = 0.5) -> None:
        super().__init__(layouts.load(layout), min_presence)
        self.presence = presence

    def detect(self, image: np.ndarray) -> list[Roi]:
        square = red_square(image)
        return [] if square is None else [square]

    def _landmarks(self, crops: list[Crop]) -> list[Person]:
        return [self._person(image, region) for image, region in crops]

    def _person(self, image: np.ndarray, region: Roi) -> Person:
        square = red_square(image, region)
        if square is None:
            return Person(np.zeros((len(self.layout), 3)), 0.0, region)
        keypoints = np.tile([*square.centre, 1.0], (len(self.layout), 1))
        return Person(keypoints, self.presence, square)


def red_square(image: np.ndarray, within: Roi | None = None) -> Roi | None:
    """The upright region (PADDING times the side) around the pure red pixels of the image,
    or of the upright box of `within`; None when there are none."""
    red = (image[..., 0] == 255) & (image[..., 1] == 0) & (image[..., 2] == 0)
    if within is not None:
        lo = np.maximum(np.floor(within.centre - within.size / 2), 0).astype(int)
        hi = np.ceil(within.centre + within.size / 2).astype(int)
        red = _window(red, lo, hi)
    ys, xs = np.nonzero(red)
    if not len(xs):
        return None
    lo, hi = np.array([xs.min(), ys.min()]), np.array([xs.max() + 1, ys.max() + 1])
    return Roi((lo + hi) / 2.0, float((hi - lo).max()) * PADDING)


def _window(mask: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The mask with everything outside columns lo[0]:hi[0] and rows lo[1]:hi[1] cleared."""
    out = np.zeros_like(mask)
    out[lo[1]:hi[1], lo[0]:hi[0]] = mask[lo[1]:hi[1], lo[0]:hi[0]]
    return out
