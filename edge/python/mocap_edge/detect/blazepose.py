"""MediaPipe BlazePose on onnxruntime (edge/models/blazepose): the person detector finds
people in the letterboxed image; the landmark model reads 33 keypoints from a rotated crop
around each, whose two auxiliary landmarks give the next frame's crop (tracking), so the
detector runs only when tracking is lost.

Inputs as MediaPipe feeds them: detector 224 x 224 RGB in [-1, 1], landmarks 256 x 256 RGB
in [0, 1] (edge/models/blazepose/README.md). Detector keypoint 0 is the hips' centre and 1
a point along the body whose distance sets the full-body scale; landmarks 33 and 34 are the
same two points for tracking. Crops: side 2 x that distance x 1.25, "up" along it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mocap_edge import resources
from mocap_edge.detect import anchors, decoders, layouts, roi
from mocap_edge.detect.base import Crop, Detector, Person
from mocap_edge.detect.onnx import OnnxNetwork

DETECTOR_SIZE, LANDMARK_SIZE = 224, 256
KEYPOINTS = 33  # plus 2 auxiliary (tracking) landmarks in the model's 39 x 5 output
NMS_IOU = 0.3  # detections overlapping more are one person (MediaPipe's)
OUTPUTS = ["Identity", "Identity_1", "Identity_3"]  # landmarks, pose flag, heatmap (64 x 64 x 39)

__all__ = ["BlazePose", "Person"]


class BlazePose(Detector):
    """models: the folder of the two ONNX files (default: mocap_edge.resources.models_dir).
    min_detection: the person detector's score threshold; min_presence: the landmark
    model's pose flag below which a tracked person is lost; tiled: the person detector also
    looks at the image's square tiles (tiles())."""

    def __init__(self, models: str | Path = "", threads: int = 2, min_detection: float = 0.5,
                 min_presence: float = 0.5, tiled: bool = True) -> None:
        super().__init__(layouts.load("blazepose33"), min_presence)
        folder = Path(models) if models else resources.models_dir("blazepose")
        self.detector = OnnxNetwork(folder / "pose_detection.onnx", threads)
        self.landmarker = OnnxNetwork(folder / "pose_landmark_full.onnx", threads)
        self.anchors = anchors.ssd_anchors()
        self.min_detection, self.tiled = min_detection, tiled

    def detect(self, image: np.ndarray) -> list[roi.Roi]:
        """Crops around the people in an RGB image: those the person detector finds in the
        whole (letterboxed) image, then, tiled, those it finds only in the image's square tiles
        (tiles(); each detector's run merged by weighted non-maximum suppression)."""
        height, width = image.shape[:2]
        whole = self._detections(image, roi.letterbox(width, height))
        more = [d for region in (tiles(width, height) if self.tiled else []) for d in self._detections(image, region)]
        more = [d for d in decoders.weighted_nms(more) if all(decoders.iou(d.box, w.box) <= NMS_IOU for w in whole)]
        return [roi.aligned(d.keypoints[0], d.keypoints[1]) for d in whole + more]

    def _detections(self, image: np.ndarray, region: roi.Roi) -> list[decoders.Detection]:
        """The person detector's on an upright region of the image, in image pixels."""
        x = region.crop(image, DETECTOR_SIZE).astype(np.float32)[None] / 127.5 - 1.0
        raw_boxes, raw_scores = self.detector.run(x, ["Identity", "Identity_1"])
        found = decoders.weighted_nms(decoders.decode_ssd(raw_boxes[0], raw_scores[0], self.anchors, DETECTOR_SIZE,
                                                          self.min_detection), NMS_IOU)
        return [decoders.Detection(region.to_image(d.box.reshape(2, 2), DETECTOR_SIZE).reshape(4),  # corners stay
                                   region.to_image(d.keypoints, DETECTOR_SIZE), d.score) for d in found]

    def _landmarks(self, crops: list[Crop]) -> list[Person]:
        """Packed into one inference (the model's batch dimension is symbolic:
        edge/models/blazepose/README.md); landmarks refined from the heatmap as MediaPipe does."""
        x = np.stack([r.crop(image, LANDMARK_SIZE) for image, r in crops]).astype(np.float32) / 255.0
        raw, flags, heatmaps = self.landmarker.run(x, OUTPUTS)
        return [_person(region, r, flag, heatmap) for (_, region), r, flag, heatmap in zip(crops, raw, flags, heatmaps)]


def tiles(width: int, height: int) -> list[roi.Roi]:
    """Square regions of the image's short side along its long side, each overlapping the
    next by half (none for an image nearly square: each would be nearly the whole).
    Letterboxed whole, a 1088 x 1920 image shrinks 8.6 times into the detector's 224 pixels
    and a person standing far back to a few dozen: missed; a tile shrinks it 4.9 times
    (Pose2Sim's multi-person trial, camera 3)."""
    short, long = sorted((width, height))
    if long < 1.25 * short:
        return []
    count = int(np.ceil(2.0 * long / short)) - 1
    starts = np.linspace(0.0, long - short, count)
    centres = [(s + short / 2.0, short / 2.0) if width > height else (short / 2.0, s + short / 2.0) for s in starts]
    return [roi.Roi(np.array(c), float(short), 0.0) for c in centres]


def _person(region: roi.Roi, raw: np.ndarray, flag: np.ndarray, heatmap: np.ndarray) -> Person:
    """A person from one crop's outputs: 39 landmarks x 5, the pose flag, the heatmap."""
    lm = raw.reshape(39, 5).astype(np.float64)
    lm[:KEYPOINTS, :2] = decoders.refine_from_heatmaps(lm[:KEYPOINTS, :2], heatmap, LANDMARK_SIZE / heatmap.shape[0])
    kp = decoders.decode_regression(lm.reshape(-1), 39)
    xy = region.to_image(kp[:, :2], LANDMARK_SIZE)
    return Person(np.column_stack([xy[:KEYPOINTS], kp[:KEYPOINTS, 2]]),
                  float(np.asarray(flag).reshape(-1)[0]),  # a probability already
                  roi.aligned(xy[33], xy[34]))
