"""People, the keypoint-model interface the tracker uses, and the registry of models.

A model is opened by name, `open_detector("blazepose")`, `open_detector("sim:streams.npz",
camera="cam0")`; the name picks the backend and the options go to its constructor:

    blazepose[:FOLDER]      MediaPipe BlazePose on onnxruntime (the default; blazepose.py)
    topdown:CONFIG.json     any top-down ONNX model described by a configuration
                            (topdown.py); a bare path ending in .json means the same
    sim:STREAMS             the simulated studio's keypoints (sim.py), with the sim: source
    fake:                   red squares are people, in-process, for tests (fake.py)
"""

from __future__ import annotations

import abc
import dataclasses

import numpy as np

from mocap_edge import registry
from mocap_edge.detect.layouts import Layout
from mocap_edge.detect.roi import Roi
from mocap_edge.errors import ModelError

# name -> "module:class or function"; imported only when opened (onnxruntime, cv2 stay out of a simulated box)
MODELS: dict[str, str] = {
    "blazepose": "mocap_edge.detect.blazepose:BlazePose",
    "topdown": "mocap_edge.detect.topdown:from_config",
    "sim": "mocap_edge.detect.sim:SimulatedDetector",
    "fake": "mocap_edge.detect.fake:FakeDetector",
}

Crop = tuple[np.ndarray, Roi]  # an image and a region of it


@dataclasses.dataclass
class Person:
    keypoints: np.ndarray  # (K, 3) image pixels x, y and confidence, in the model's layout
    presence: float  # in [0, 1]: a person is in the crop (the model's own flag or score)
    next_roi: Roi  # where to look in the next frame


class Detector(abc.ABC):
    """A top-down keypoint model: `detect` finds people's regions in a whole image (run only
    when tracking is lost), `landmarks` reads the keypoints in regions of any images at once
    (one inference for every camera's people). Backends fill in `detect` and `_landmarks`.
    A person whose presence is below `min_presence` is not one (the tracker drops it)."""

    def __init__(self, layout: Layout, min_presence: float = 0.5) -> None:
        if not 0.0 <= min_presence <= 1.0:
            raise ModelError(f"min_presence must be in [0, 1], got {min_presence}")
        self.layout = layout
        self.min_presence = min_presence

    @abc.abstractmethod
    def detect(self, image: np.ndarray) -> list[Roi]:
        """Regions around the people in an RGB image."""

    @abc.abstractmethod
    def _landmarks(self, crops: list[Crop]) -> list[Person]:
        """One person per crop (crops is not empty)."""

    def landmarks(self, crops: list[Crop]) -> list[Person]:
        """One person per (image, region) pair, in order."""
        if not crops:
            return []
        people = self._landmarks(crops)
        if len(people) != len(crops):
            raise RuntimeError(f"{type(self).__name__} returned {len(people)} people for {len(crops)} crops")
        return people


def open_detector(spec: str = "blazepose", **options: object) -> Detector:
    """The model named by `spec` (module docstring) built with the backend's keyword
    options; raises ModelError with the reason."""
    if spec.partition(":")[0] not in MODELS and spec.endswith(".json"):
        spec = f"topdown:{spec}"
    return registry.open_backend(MODELS, spec, ModelError, "keypoint model", **options)
