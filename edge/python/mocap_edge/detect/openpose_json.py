"""OpenPose-style JSON, one file per frame: the interchange format Pose2Sim, FreeMoCap and
EasyMocap read. `people[].pose_keypoints_2d` is x, y, confidence per keypoint of the
model's layout (a missing keypoint is 0, 0, 0), named in the file ("keypoint_layout",
"keypoint_names") since BlazePose's 33 are not OpenPose's BODY_25."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

LAYOUT = "blazepose33"
NAMES = ["nose", "left_eye_inner", "left_eye", "left_eye_outer", "right_eye_inner", "right_eye", "right_eye_outer",
         "left_ear", "right_ear", "mouth_left", "mouth_right", "left_shoulder", "right_shoulder", "left_elbow",
         "right_elbow", "left_wrist", "right_wrist", "left_pinky", "right_pinky", "left_index", "right_index",
         "left_thumb", "right_thumb", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle",
         "left_heel", "right_heel", "left_foot_index", "right_foot_index"]


def frame_file(folder: Path, stem: str, index: int) -> Path:
    return Path(folder) / f"{stem}_{index:012d}_keypoints.json"


def write_frame(path: Path, people: list[np.ndarray], index: int, capture_time_ns: int,
                min_confidence: float = 0.0) -> None:
    """people: (33, 3) x, y, confidence each; keypoints at or below min_confidence are written 0, 0, 0."""
    out = []
    for k in people:
        k = np.where((k[:, 2] > min_confidence)[:, None], k, 0.0)
        out.append({"person_id": [-1], "pose_keypoints_2d": [round(float(v), 3) for v in k.reshape(-1)],
                    "face_keypoints_2d": [], "hand_left_keypoints_2d": [], "hand_right_keypoints_2d": []})
    Path(path).write_text(json.dumps({"version": 1.3, "keypoint_layout": LAYOUT, "keypoint_names": NAMES,
                                      "frame_index": index, "capture_time_ns": capture_time_ns, "people": out}))


def read_frame(path: Path) -> list[np.ndarray]:
    """(K, 3) per person of an OpenPose-style file (any layout)."""
    data = json.loads(Path(path).read_text())
    return [np.asarray(p["pose_keypoints_2d"], np.float64).reshape(-1, 3) for p in data.get("people", [])]
