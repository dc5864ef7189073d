"""Decoders from model outputs to keypoints, for the three kinds of pose models a studio
may drop in by configuration:

- `decode_ssd`: single-shot detector boxes with keypoints (BlazePose's person detector);
- `decode_regression`: keypoints regressed directly in input pixels (BlazePose landmarks);
- `decode_heatmaps`: one heatmap per keypoint (CPM / HRNet style), argmax refined by a
  quarter-pixel step towards the larger neighbour;
- `decode_simcc`: one 1-D classification per axis (RTMPose style), argmax / split ratio.
All return keypoints in the model input's pixels with a confidence in [0, 1].
"""

from __future__ import annotations

import dataclasses

import numpy as np


def sigmoid(x: np.ndarray, clip: float = 100.0) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-np.clip(x, -clip, clip)))


@dataclasses.dataclass(frozen=True)
class Detection:
    box: np.ndarray  # (4,) x_min, y_min, x_max, y_max, input pixels
    keypoints: np.ndarray  # (K, 2) input pixels
    score: float


def decode_ssd(raw_boxes: np.ndarray, raw_scores: np.ndarray, anchors: np.ndarray, input_size: int,
               min_score: float = 0.5) -> list[Detection]:
    """Boxes and keypoints of the anchors scoring above min_score. raw_boxes (N, 4 + 2K):
    centre offset x, y, width, height, then keypoint offsets x, y — in input pixels, relative
    to the anchor centre; raw_scores (N,) or (N, 1) logits."""
    scores = sigmoid(np.asarray(raw_scores, np.float64).reshape(-1))
    keep = np.flatnonzero(scores >= min_score)
    out = []
    for i in keep:
        r = raw_boxes[i].astype(np.float64)
        centre = anchors[i] * input_size + r[0:2]
        half = r[2:4] / 2
        keypoints = anchors[i] * input_size + r[4:].reshape(-1, 2)
        out.append(Detection(np.concatenate([centre - half, centre + half]), keypoints, float(scores[i])))
    return out


def iou(a: np.ndarray, b: np.ndarray) -> float:
    w = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    h = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = w * h
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / union if union > 0 else 0.0


def weighted_nms(detections: list[Detection], min_iou: float = 0.3) -> list[Detection]:
    """MediaPipe's weighted non-maximum suppression: the best detection of each cluster of
    overlapping ones, its box and keypoints replaced by the score-weighted mean of the cluster."""
    remaining = sorted(detections, key=lambda d: -d.score)
    out = []
    while remaining:
        best = remaining[0]
        cluster = [d for d in remaining if iou(best.box, d.box) > min_iou]
        remaining = [d for d in remaining if iou(best.box, d.box) <= min_iou]
        w = np.array([d.score for d in cluster])
        box = np.einsum("n,ni->i", w, np.array([d.box for d in cluster])) / w.sum()
        keypoints = np.einsum("n,nij->ij", w, np.array([d.keypoints for d in cluster])) / w.sum()
        out.append(Detection(box, keypoints, best.score))
    return out


def decode_regression(raw: np.ndarray, keypoints: int, values: int = 5) -> np.ndarray:
    """(K, 3) x, y, confidence from a flat (K * values) vector of x, y, z, visibility,
    presence (logits): the confidence is visibility x presence, as probabilities."""
    r = np.asarray(raw, np.float64).reshape(keypoints, values)
    conf = sigmoid(r[:, 3]) * (sigmoid(r[:, 4]) if values > 4 else 1.0)
    return np.column_stack([r[:, 0], r[:, 1], conf])


def refine_from_heatmaps(points: np.ndarray, heatmaps: np.ndarray, stride: float, kernel: int = 7,
                         min_confidence: float = 0.5) -> np.ndarray:
    """MediaPipe's RefineLandmarksFromHeatmap: each point (K, 2+) moved to the sigmoid-weighted
    mean of the kernel x kernel heatmap cells around its own cell, when the window's largest
    weight reaches min_confidence. heatmaps (H, W, >= K) logits; stride: input pixels per cell."""
    out = np.array(points, np.float64)
    h, w = heatmaps.shape[:2]
    half = kernel // 2
    for j in range(len(out)):
        cx, cy = int(out[j, 0] // stride), int(out[j, 1] // stride)
        x0, x1, y0, y1 = max(cx - half, 0), min(cx + half + 1, w), max(cy - half, 0), min(cy + half + 1, h)
        if x0 >= x1 or y0 >= y1:
            continue
        weights = sigmoid(heatmaps[y0:y1, x0:x1, j].astype(np.float64))
        if weights.max() < min_confidence:
            continue
        rows, cols = np.mgrid[y0:y1, x0:x1]
        out[j, 0] = stride * (cols * weights).sum() / weights.sum()
        out[j, 1] = stride * (rows * weights).sum() / weights.sum()
    return out


def decode_heatmaps(heatmaps: np.ndarray, input_size: tuple[int, int]) -> np.ndarray:
    """(K, 3) from (K, H, W) heatmaps; confidence = the peak value, clipped to [0, 1]."""
    k, h, w = heatmaps.shape
    flat = heatmaps.reshape(k, -1)
    peak = flat.argmax(axis=1)
    y, x = np.divmod(peak, w)
    xs, ys = x.astype(np.float64), y.astype(np.float64)
    for j in range(k):  # quarter-pixel step towards the higher neighbour
        hm = heatmaps[j]
        if 0 < x[j] < w - 1:
            xs[j] += 0.25 * np.sign(hm[y[j], x[j] + 1] - hm[y[j], x[j] - 1])
        if 0 < y[j] < h - 1:
            ys[j] += 0.25 * np.sign(hm[y[j] + 1, x[j]] - hm[y[j] - 1, x[j]])
    scale = np.array([input_size[0] / w, input_size[1] / h])
    xy = (np.column_stack([xs, ys]) + 0.5) * scale - 0.5
    return np.column_stack([xy, np.clip(flat.max(axis=1), 0, 1)])


def decode_simcc(simcc_x: np.ndarray, simcc_y: np.ndarray, split_ratio: float = 2.0) -> np.ndarray:
    """(K, 3) from (K, Wx) and (K, Wy) classification vectors; confidence = the smaller of
    the two maxima (RTMPose's convention), clipped to [0, 1]."""
    x, y = simcc_x.argmax(axis=1) / split_ratio, simcc_y.argmax(axis=1) / split_ratio
    conf = np.minimum(simcc_x.max(axis=1), simcc_y.max(axis=1))
    return np.column_stack([x, y, np.clip(conf, 0, 1)])
