"""A 2D keypoint detector's errors, per keypoint layout.

Systematic: each keypoint is a site 1-3 cm off the solver's nominal site, in a random
direction fixed per subject (a detector's "hip" is not the hip joint).
Random, per detection: Student-t (4 degrees of freedom) noise with a standard deviation
of 1% of the subject's projected height; 2% of frames per camera swap left and right;
3% of detections are gross outliers anywhere in the subject's box (enlarged by 50%).
No detection when the keypoint is outside the image or hidden by the body (occlusion.py).
Confidence falls with the error: c = 0.95 exp(-(e / 4 sigma)^2) + U(-0.05, 0.05), in
[0.05, 1].
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np


@dataclasses.dataclass(frozen=True)
class DetectorErrors:
    offset_range: tuple[float, float] = (0.01, 0.03)  # m, systematic site offsets
    sigma_fraction: float = 0.01  # of the projected subject height
    dof: float = 4.0  # Student-t degrees of freedom (heavy tails)
    swap_rate: float = 0.02  # per camera frame
    outlier_rate: float = 0.03  # per detection
    site_offsets: bool = True
    random: bool = True  # False: only the systematic errors act


def mirror(names: list[str]) -> np.ndarray:
    """Index of each keypoint's left/right twin (itself when it has none)."""
    def twin(name: str) -> str:
        swapped = re.sub(r"(?i)(left|right)", lambda m: {"left": "right", "right": "left",
                                                          "Left": "Right", "Right": "Left"}[m.group(1)], name)
        if swapped == name and len(name) > 1 and name[0] in "LR" and name[1].isupper():
            swapped = {"L": "R", "R": "L"}[name[0]] + name[1:]
        return swapped
    index = {n: i for i, n in enumerate(names)}
    return np.array([index.get(twin(n), i) for i, n in enumerate(names)])


def site_offsets(n: int, errors: DetectorErrors, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) systematic offsets (bone frame, m): one draw per subject."""
    if not errors.site_offsets:
        return np.zeros((n, 3))
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True) * rng.uniform(*errors.offset_range, size=(n, 1))


def detect(pixels: np.ndarray, visible: np.ndarray, twins: np.ndarray, size: tuple[int, int],
           errors: DetectorErrors, rng: np.random.Generator) -> np.ndarray:
    """(K, 3) detections [x, y, confidence] of one camera frame from the true pixels (K, 2)."""
    out = np.zeros((len(pixels), 3))
    if not visible.any():
        return out
    box_lo, box_hi = pixels[visible].min(axis=0), pixels[visible].max(axis=0)
    sigma = max(errors.sigma_fraction * (box_hi[1] - box_lo[1]), 0.5)
    seen = pixels.copy()
    if errors.random:
        seen += sigma / np.sqrt(errors.dof / (errors.dof - 2)) * rng.standard_t(errors.dof, size=seen.shape)
        if rng.random() < errors.swap_rate:
            seen = seen[twins]
        gross = rng.random(len(seen)) < errors.outlier_rate
        pad = 0.25 * (box_hi - box_lo)
        seen[gross] = rng.uniform(box_lo - pad, box_hi + pad, size=(gross.sum(), 2))
    err = np.linalg.norm(seen - pixels, axis=1)
    conf = 0.95 * np.exp(-((err / (4 * sigma)) ** 2)) + (rng.uniform(-0.05, 0.05, len(err)) if errors.random else 0)
    inside = (seen[:, 0] >= 0) & (seen[:, 0] < size[0]) & (seen[:, 1] >= 0) & (seen[:, 1] < size[1])
    keep = visible & visible[twins] & inside if errors.random else visible & inside
    out[keep, :2] = seen[keep]
    out[keep, 2] = np.clip(conf[keep], 0.05, 1.0)
    return out
