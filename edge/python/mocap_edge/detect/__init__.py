"""On-device keypoint detection: one interface (`Detector`: find people, read their
keypoints) with a registry of models opened by name — BlazePose and any top-down ONNX model
on onnxruntime, the simulated studio's keypoints, an in-process fake (see base.py) — the
tracker that runs them (tracking.py), model-agnostic decoders (SSD boxes with keypoints,
heatmaps, SimCC, direct regression) and rotated regions of interest."""

from mocap_edge.detect.base import MODELS, Detector, Person, open_detector

__all__ = ["MODELS", "Detector", "Person", "open_detector"]
