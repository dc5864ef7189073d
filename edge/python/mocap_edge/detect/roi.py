"""Rotated square regions of interest and the crops a model sees.

Coordinates are continuous pixels: pixel k covers [k, k + 1), its centre is k + 0.5 (model
outputs normalised by the input size use the same convention). A region has a centre, a
side and a rotation r: its x axis in the image is u = (cos r, sin r) and its y axis (down)
v = (-sin r, cos r), so r = 0 is upright and "up" in the crop is -v.
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class Roi:
    centre: np.ndarray  # (2,) image pixels
    size: float  # side, image pixels
    rotation: float = 0.0  # radians

    def axes(self) -> np.ndarray:
        c, s = np.cos(self.rotation), np.sin(self.rotation)
        return np.array([[c, -s], [s, c]])  # columns u, v

    def extent(self, crop_size: int | tuple[int, int]) -> tuple[tuple[int, int], np.ndarray]:
        """The crop's (width, height) in pixels and the region's sides (along u, along v) in
        image pixels: `size` is the side along v; a non-square crop widens or narrows u."""
        w, h = (crop_size, crop_size) if isinstance(crop_size, int) else crop_size
        return (w, h), np.array([self.size * w / h, self.size])

    def to_image(self, points: np.ndarray, crop_size: int | tuple[int, int]) -> np.ndarray:
        """(N, 2) crop pixels -> image pixels."""
        wh, sides = self.extent(crop_size)
        local = (np.asarray(points, np.float64) / wh - 0.5) * sides
        return self.centre + local @ self.axes().T

    def to_crop(self, points: np.ndarray, crop_size: int | tuple[int, int]) -> np.ndarray:
        """(N, 2) image pixels -> crop pixels."""
        wh, sides = self.extent(crop_size)
        local = (np.asarray(points, np.float64) - self.centre) @ self.axes()
        return (local / sides + 0.5) * wh

    def crop(self, image: np.ndarray, crop_size: int | tuple[int, int]) -> np.ndarray:
        """The region resampled to the crop size (bilinear, zero outside the image)."""
        import cv2  # here, not at the top: a simulated box never crops and starts without OpenCV

        wh, sides = self.extent(crop_size)
        a = self.axes() * (sides / wh)  # column j scaled by image pixels per crop pixel along it
        # crop index (i, j) -> image index: continuous coords are index + 0.5 on both sides.
        b = self.to_image(np.array([[0.5, 0.5]]), crop_size)[0] - 0.5
        m = np.hstack([a, b[:, None]])
        return cv2.warpAffine(image, m, wh, flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                              borderMode=cv2.BORDER_CONSTANT, borderValue=0)


def letterbox(width: int, height: int) -> Roi:
    """The upright square around the whole image (a detector's letterboxed input)."""
    return Roi(np.array([width / 2.0, height / 2.0]), float(max(width, height)), 0.0)


def aligned(centre: np.ndarray, towards: np.ndarray, scale: float = 1.25) -> Roi:
    """MediaPipe's alignment-points region: centred on `centre`, side 2 |towards - centre|
    times `scale`, rotated so that `towards` is straight up in the crop."""
    d = np.asarray(towards, np.float64) - np.asarray(centre, np.float64)
    return Roi(np.asarray(centre, np.float64), 2.0 * float(np.hypot(*d)) * scale, float(np.arctan2(d[0], -d[1])))
