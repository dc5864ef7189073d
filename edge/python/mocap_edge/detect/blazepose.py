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

import dataclasses
from pathlib import Path

import numpy as np
import onnxruntime as ort

from mocap_edge.detect import anchors, decoders, layouts, roi

MODELS = Path(__file__).resolve().parents[3] / "models" / "blazepose"
DETECTOR_SIZE, LANDMARK_SIZE = 224, 256
KEYPOINTS = 33  # plus 2 auxiliary (tracking) landmarks in the model's 39 x 5 output
OUTPUTS = ["Identity", "Identity_1", "Identity_3"]  # landmarks, pose flag, heatmap (64 x 64 x 39)



@dataclasses.dataclass
class Person:
    keypoints: np.ndarray  # (K, 3) image pixels x, y and confidence, in the model's layout
    presence: float  # the landmark model's pose flag: a person is in the crop
    next_roi: roi.Roi  # where to look in the next frame


def onnx_session(path: Path, threads: int) -> ort.InferenceSession:
    options = ort.SessionOptions()
    options.intra_op_num_threads = threads
    options.inter_op_num_threads = 1
    return ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])


class BlazePose:
    def __init__(self, models: Path = MODELS, threads: int = 2, min_detection: float = 0.5):
        self.detector = onnx_session(models / "pose_detection.onnx", threads)
        self.landmarker = onnx_session(models / "pose_landmark_full.onnx", threads)
        self.anchors = anchors.ssd_anchors()
        self.layout = layouts.load("blazepose33")
        self.min_detection = min_detection
        self._landmark_input = self.landmarker.get_inputs()[0].name
        batch = self.landmarker.get_inputs()[0].shape[0]
        self.batchable = not isinstance(batch, int) or batch != 1  # a symbolic batch dimension

    def detect(self, image: np.ndarray) -> list[roi.Roi]:
        """Crops around the people in an RGB image (the full-image person detector)."""
        box = roi.letterbox(image.shape[1], image.shape[0])
        x = box.crop(image, DETECTOR_SIZE).astype(np.float32)[None] / 127.5 - 1.0
        raw_boxes, raw_scores = self.detector.run(["Identity", "Identity_1"], {self.detector.get_inputs()[0].name: x})
        found = decoders.weighted_nms(decoders.decode_ssd(raw_boxes[0], raw_scores[0], self.anchors, DETECTOR_SIZE,
                                                          self.min_detection))
        out = []
        for d in found:
            kp = box.to_image(d.keypoints, DETECTOR_SIZE)
            out.append(roi.aligned(kp[0], kp[1]))
        return out

    def landmarks(self, crops: list[tuple[np.ndarray, roi.Roi]]) -> list[Person]:
        """People from (image, region) pairs — regions of any images, packed into one
        inference (the model's batch dimension is symbolic: edge/models/blazepose/README.md).
        Landmarks are refined from the heatmap as MediaPipe does."""
        if not crops:
            return []
        x = np.stack([r.crop(image, LANDMARK_SIZE) for image, r in crops]).astype(np.float32) / 255.0
        if self.batchable:
            runs = [self.landmarker.run(OUTPUTS, {self._landmark_input: x})]
        else:
            runs = [self.landmarker.run(OUTPUTS, {self._landmark_input: x[i:i + 1]}) for i in range(len(x))]
        raw, flags, heatmaps = (np.concatenate([r[k] for r in runs]) for k in range(3))
        people = []
        for (_, region), r, flag, heatmap in zip(crops, raw, flags, heatmaps):
            lm = r.reshape(39, 5).astype(np.float64)
            lm[:KEYPOINTS, :2] = decoders.refine_from_heatmaps(lm[:KEYPOINTS, :2], heatmap, LANDMARK_SIZE / heatmap.shape[0])
            kp = decoders.decode_regression(lm.reshape(-1), 39)
            xy = region.to_image(kp[:, :2], LANDMARK_SIZE)
            people.append(Person(np.column_stack([xy[:KEYPOINTS], kp[:KEYPOINTS, 2]]),
                                 float(np.asarray(flag).reshape(-1)[0]),  # a probability already
                                 roi.aligned(xy[33], xy[34])))
        return people
