"""`mocap detect VIDEO --out DIR`: the edge pipeline (BlazePose with region tracking) on a
video file, one OpenPose-style JSON per frame."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from mocap_edge.detect import openpose_json
from mocap_edge.detect.base import Detector, open_detector
from mocap_edge.detect.tracking import Tracker
from mocap_edge.sources.base import Frame, open_source


def detect_frames(video: Path, tracker: Tracker) -> Iterator[tuple[Frame, list[np.ndarray], float]]:
    """Each frame of the video with its people's (K, 3) keypoints (x, y, confidence) and the
    video's nominal frame rate."""
    with open_source(f"video:{video}") as source:
        for frame in source:
            yield frame, [p.keypoints for p in tracker.step({"cam": frame.image})["cam"]], source.nominal_fps


def open_tracker(model: str | Detector = "blazepose", max_people: int = 2, threads: int = 2) -> Tracker:
    """model: a model's name (detect/base.py): "blazepose" or a model configuration file
    (topdown.py); threads: the inference's."""
    return Tracker(open_detector(model, threads=threads) if isinstance(model, str) else model, max_people=max_people)


def detect_video(video: Path, out: Path, max_people: int = 2, model: str = "blazepose") -> dict:
    """Writes out/<stem>_<frame>_keypoints.json for every frame; returns counts."""
    out.mkdir(parents=True, exist_ok=True)
    tracker = open_tracker(model, max_people)
    frames = people = 0
    for frame, found, _ in detect_frames(video, tracker):
        openpose_json.write_frame(openpose_json.frame_file(out, Path(video).stem, frame.index), found, frame.index,
                                  frame.capture_time_ns, tracker.model.layout)
        frames += 1
        people += len(found)
    return {"video": str(video), "frames": frames, "people": people, "detector_runs": tracker.counts.detector_runs,
            "out": str(out)}
