"""The subject among the people a camera sees: per camera, the person nearest the previous
frame's choice, the largest one to start with or after a gap. A take folder's solve and the
calibration from the streams choose it so."""

from __future__ import annotations

import numpy as np

LAYOUT_SIZES = {"coco17": 17, "body25b": 25, "blazepose33": 33}  # keypoints per layout


def box_size(k: np.ndarray) -> float:
    """The larger side of the box around a person's detected keypoints (K, 3), pixels."""
    v = k[k[:, 2] > 0, :2]
    return float((v.max(axis=0) - v.min(axis=0)).max()) if len(v) > 1 else 0.0


def _nearest(persons: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """The person whose keypoints seen in both lie nearest (median pixel distance) previous's."""
    def distance(p: np.ndarray) -> float:
        both = (p[:, 2] > 0) & (previous[:, 2] > 0)
        return np.median(np.linalg.norm(p[both, :2] - previous[both, :2], axis=1)) if both.any() else np.inf
    return min(persons, key=distance)


def choose_subject(people: list, n_frames: int, k: int) -> np.ndarray:
    """(F, C, K, 3) the subject's keypoints from people[camera][frame] (P, K, 3) (zeros where a
    camera saw nobody): per camera, the person nearest the previous frame's choice, the
    largest one to start with or after a gap."""
    out = np.zeros((n_frames, len(people), k, 3))
    for c, frames in enumerate(people):
        previous = None
        for f, persons in enumerate(frames):
            if len(persons) == 0:
                previous = None
                continue
            chosen = max(persons, key=box_size) if previous is None else _nearest(persons, previous)
            out[f, c] = previous = chosen
    return out
