"""OpenPose-style JSON, one file per frame: the interchange format Pose2Sim, FreeMoCap and
EasyMocap read. `people[].pose_keypoints_2d` is x, y, confidence per keypoint of the
model's layout (a missing keypoint is 0, 0, 0), named in the file ("keypoint_layout",
"keypoint_names"): BlazePose's 33 are not OpenPose's BODY_25."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from mocap_edge.detect.layouts import Layout



def frame_file(folder: Path, stem: str, index: int) -> Path:
    return Path(folder) / f"{stem}_{index:012d}_keypoints.json"


def write_frame(path: Path, people: list[np.ndarray], index: int, capture_time_ns: int, layout: Layout,
                min_confidence: float = 0.0) -> None:
    """people: (K, 3) x, y, confidence each; keypoints at or below min_confidence are written 0, 0, 0."""
    out = []
    for k in people:
        k = np.where((k[:, 2] > min_confidence)[:, None], k, 0.0)
        out.append({"person_id": [-1], "pose_keypoints_2d": [round(float(v), 3) for v in k.reshape(-1)],
                    "face_keypoints_2d": [], "hand_left_keypoints_2d": [], "hand_right_keypoints_2d": []})
    Path(path).write_text(json.dumps({"version": 1.3, "keypoint_layout": layout.name, "keypoint_names": layout.names,
                                      "frame_index": index, "capture_time_ns": capture_time_ns, "people": out}))


def box_size(k: np.ndarray) -> float:
    """The larger side of the box around a person's detected keypoints (K, 3), pixels."""
    v = k[k[:, 2] > 0, :2]
    return float((v.max(axis=0) - v.min(axis=0)).max()) if len(v) > 1 else 0.0


def largest_people(folder: Path) -> list[np.ndarray]:
    """(K, 3) the largest person of each file of a pose folder, in frame order (zeros where
    the file has nobody)."""
    out = []
    for path in sorted(Path(folder).glob("*.json")):
        people = read_frame(path)
        out.append(max(people, key=box_size) if people else np.zeros((0, 3)))
    return out


def read_frame(path: Path) -> list[np.ndarray]:
    """(K, 3) per person of an OpenPose-style file (any layout)."""
    data = json.loads(Path(path).read_text())
    return [np.asarray(p["pose_keypoints_2d"], np.float64).reshape(-1, 3) for p in data.get("people", [])]
