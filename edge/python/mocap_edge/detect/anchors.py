"""SSD anchors as MediaPipe's SsdAnchorsCalculator lays them out (fixed anchor size: every
anchor is a 1 x 1 box centred on its feature-map cell; one anchor per aspect ratio plus an
interpolated scale, i.e. two per cell and layer, and layers of equal stride merged)."""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class AnchorOptions:
    input_size: int = 224
    strides: tuple[int, ...] = (8, 16, 32, 32, 32)
    anchors_per_layer: int = 2  # aspect ratio 1.0 and the interpolated scale
    offset: float = 0.5


BLAZEPOSE_DETECTOR = AnchorOptions()  # 2254 anchors: 28x28x2 + 14x14x2 + 7x7x6


def ssd_anchors(options: AnchorOptions = BLAZEPOSE_DETECTOR) -> np.ndarray:
    """(N, 2) anchor centres, normalised to [0, 1] of the input, in the model's output order."""
    centres = []
    layer = 0
    while layer < len(options.strides):
        stride = options.strides[layer]
        same = 0  # consecutive layers of one stride share a feature map
        while layer < len(options.strides) and options.strides[layer] == stride:
            same += 1
            layer += 1
        cells = int(np.ceil(options.input_size / stride))
        y, x = np.meshgrid(np.arange(cells), np.arange(cells), indexing="ij")
        grid = np.stack([(x + options.offset) / cells, (y + options.offset) / cells], axis=-1).reshape(-1, 2)
        centres.append(np.repeat(grid, same * options.anchors_per_layer, axis=0))
    return np.concatenate(centres)
