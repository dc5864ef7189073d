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



@dataclasses.dataclass
class Person:
    keypoints: np.ndarray  # (33, 3) image pixels x, y and confidence
    presence: float  # the landmark model's pose flag: a person is in the crop
    next_roi: roi.Roi  # where to look in the next frame


def _session(path: Path, threads: int) -> ort.InferenceSession:
    options = ort.SessionOptions()
    options.intra_op_num_threads = threads
    options.inter_op_num_threads = 1
    return ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])


class BlazePose:
    def __init__(self, models: Path = MODELS, threads: int = 2, min_detection: float = 0.5):
        self.detector = _session(models / "pose_detection.onnx", threads)
        self.landmarker = _session(models / "pose_landmark_full.onnx", threads)
        self.anchors = anchors.ssd_anchors()
        self.layout = layouts.load("blazepose33")
        self.min_detection = min_detection
        batch = self.landmarker.get_inputs()[0].shape[0]
        self.batchable = not isinstance(batch, int) or batch != 1  # a symbolic batch dimension

    def detect(self, image: np.ndarray) -> list[roi.Roi]:
        """Crops around the people in an RGB image (the full-image person detector)."""
        box = roi.letterbox(image.shape[1], image.shape[0])
        x = box.crop(image, DETECTOR_SIZE).astype(np.float32)[None] / 127.5 - 1.0
        raw_boxes, raw_scores = self._outputs(self.detector, x, [(12,), (1,)])
        found = decoders.weighted_nms(decoders.decode_ssd(raw_boxes[0], raw_scores[0], self.anchors, DETECTOR_SIZE,
                                                          self.min_detection))
        out = []
        for d in found:
            kp = box.to_image(d.keypoints, DETECTOR_SIZE)
            out.append(roi.aligned(kp[0], kp[1]))
        return out

    def landmarks(self, crops: list[tuple[np.ndarray, roi.Roi]]) -> list[Person]:
        """People from (image, region) pairs — regions of any images, inferred together in one
        batch when the model takes one (the paper's packing), else one by one."""
        if not crops:
            return []
        x = np.stack([r.crop(image, LANDMARK_SIZE) for image, r in crops]).astype(np.float32) / 255.0
        if self.batchable:
            raw, flags = self._outputs(self.landmarker, x, [(195,), (1,)])
        else:
            parts = [self._outputs(self.landmarker, x[i:i + 1], [(195,), (1,)]) for i in range(len(x))]
            raw, flags = np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
        people = []
        for (_, region), r, flag in zip(crops, raw, flags):
            kp = decoders.decode_regression(r, 39)
            xy = region.to_image(kp[:, :2], LANDMARK_SIZE)
            people.append(Person(np.column_stack([xy[:KEYPOINTS], kp[:KEYPOINTS, 2]]),
                                 float(np.asarray(flag).reshape(-1)[0]),  # a probability already
                                 roi.aligned(xy[33], xy[34])))
        return people

    @staticmethod
    def _outputs(session: ort.InferenceSession, x: np.ndarray, shapes: list[tuple[int, ...]]) -> list[np.ndarray]:
        """The outputs whose trailing shape is each of `shapes`, by shape (names differ
        between conversions)."""
        outs = session.run(None, {session.get_inputs()[0].name: x})
        picked = []
        for shape in shapes:
            match = [o for o in outs if tuple(o.shape[-len(shape):]) == shape and o.ndim == len(shape) + 1 + (len(shape) == 1 and o.ndim == 3)]
            picked.append(match[0] if match else next(o for o in outs if o.shape[-1] == shape[-1]))
        return picked
