"""Any top-down keypoint model in ONNX, by configuration, so a studio can drop in another
model than BlazePose. People are found by BlazePose's person detector and tracked in
rotated regions (as BlazePose's landmarks are); each region is cropped to the model's
input, the output decoded by one of the decoders (regression, heatmap, SimCC) and mapped
back to the image; the next frame's region is the box around the confident keypoints in the
region's own axes, times `padding`.

Configuration (JSON): {"format": "mocap.edge-model/1", "onnx": path (relative to the file),
  "layout": "coco17" | "blazepose33" | "body25b", "input": [width, height],
  "channels_first": bool, "rgb": bool, "mean": [3], "std": [3] (pixel values 0-255; input =
  (pixel - mean) / std), "decoder": "regression" | "heatmap" | "simcc",
  "values_per_keypoint": 5 (regression), "split_ratio": 2.0 (simcc), "padding": 1.25,
  "min_presence": 0.3 (a tracked person whose mean keypoint confidence is below it is lost)}
Opened as `open_detector("topdown:model.json")` (or the bare path; detect/base.py).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from mocap_edge.detect import decoders, layouts, roi
from mocap_edge.detect.base import Crop, Detector, Person
from mocap_edge.detect.blazepose import BlazePose
from mocap_edge.detect.onnx import OnnxNetwork
from mocap_edge.errors import ModelError

__all__ = ["ModelConfig", "TopDownModel", "from_config"]


@dataclasses.dataclass(frozen=True)
class ModelConfig:
    onnx: Path
    layout: str
    input: tuple[int, int]
    decoder: str
    channels_first: bool = True
    rgb: bool = True
    mean: tuple[float, float, float] = (0.0, 0.0, 0.0)
    std: tuple[float, float, float] = (1.0, 1.0, 1.0)
    values_per_keypoint: int = 3
    split_ratio: float = 2.0
    padding: float = 1.25
    min_presence: float = 0.3

    @staticmethod
    def load(path: Path) -> ModelConfig:
        try:
            data = json.loads(Path(path).read_text())
            if data.pop("format", None) != "mocap.edge-model/1":
                raise ValueError("format is not mocap.edge-model/1")
            data["onnx"] = Path(path).parent / data["onnx"]
            data["input"] = tuple(data["input"])
            config = ModelConfig(**data)
        except (OSError, ValueError, TypeError, KeyError) as e:
            raise ModelError(f"{path}: not a model configuration ({e})") from None
        if config.decoder not in ("regression", "heatmap", "simcc"):
            raise ModelError(f"{path}: unknown decoder {config.decoder!r}")
        return config


class TopDownModel(Detector):
    """people: the person detector (default BlazePose's; any Detector's `detect`)."""

    def __init__(self, config: ModelConfig, threads: int = 2, people: Detector | None = None) -> None:
        super().__init__(layouts.load(config.layout), config.min_presence)
        self.config = config
        self.network = OnnxNetwork(config.onnx, threads)
        self.people = people or BlazePose(threads=threads)

    def detect(self, image: np.ndarray) -> list[roi.Roi]:
        return self.people.detect(image)

    def _landmarks(self, crops: list[Crop]) -> list[Person]:
        outputs = self.network.run(self._input(crops))
        return [self._person(region, [o[i] for o in outputs]) for i, (_, region) in enumerate(crops)]

    def _input(self, crops: list[Crop]) -> np.ndarray:
        """The crops as the network's input batch: resampled, normalised, channels ordered."""
        c = self.config
        x = np.stack([r.crop(image if c.rgb else image[..., ::-1], c.input) for image, r in crops]).astype(np.float32)
        x = (x - np.float32(c.mean)) / np.float32(c.std)
        return x.transpose(0, 3, 1, 2) if c.channels_first else x

    def _person(self, region: roi.Roi, outputs: list[np.ndarray]) -> Person:
        kp = self._decode(outputs)
        xy = region.to_image(kp[:, :2], self.config.input)
        return Person(np.column_stack([xy, kp[:, 2]]), float(kp[:, 2].mean()), self._next_region(region, kp))

    def _decode(self, outputs: list[np.ndarray]) -> np.ndarray:
        c, k = self.config, len(self.layout)
        if c.decoder == "regression":
            return decoders.decode_regression(outputs[0].reshape(-1)[: k * c.values_per_keypoint], k,
                                              c.values_per_keypoint)
        if c.decoder == "heatmap":
            maps = outputs[0] if outputs[0].shape[0] == k else np.moveaxis(outputs[0], -1, 0)
            return decoders.decode_heatmaps(maps[:k], c.input)
        return decoders.decode_simcc(outputs[0][:k], outputs[1][:k], c.split_ratio)

    def _next_region(self, region: roi.Roi, kp: np.ndarray) -> roi.Roi:
        """The box around the confident keypoints, in the region's axes, times padding."""
        seen = kp[kp[:, 2] > 0.3, :2]
        if len(seen) < 2:
            return region
        local = region.to_crop(region.to_image(seen, self.config.input), self.config.input)
        lo, hi = local.min(axis=0), local.max(axis=0)
        (w, h), sides = region.extent(self.config.input)
        centre = region.to_image(((lo + hi) / 2)[None], self.config.input)[0]
        size = max((hi - lo)[1] / h * sides[1], (hi - lo)[0] / w * sides[0] * h / w) * self.config.padding
        return roi.Roi(centre, float(size), region.rotation)


def from_config(path: str, threads: int = 2) -> TopDownModel:
    """The model a configuration file (module docstring) describes."""
    return TopDownModel(ModelConfig.load(Path(path)), threads)
