"""`mocap detect VIDEO --out DIR`: the edge pipeline (BlazePose with region tracking) on a
video file, one OpenPose-style JSON per frame."""

from __future__ import annotations

from pathlib import Path

from mocap_edge.detect import openpose_json
from mocap_edge.detect.base import open_detector
from mocap_edge.detect.tracking import Tracker
from mocap_edge.sources.base import open_source


def detect_video(video: Path, out: Path, max_people: int = 2, model: str = "blazepose") -> dict:
    """Writes out/<stem>_<frame>_keypoints.json for every frame; returns counts. model:
    a model's name (detect/base.py): "blazepose" or a model configuration file (topdown.py)."""
    out.mkdir(parents=True, exist_ok=True)
    tracker = Tracker(open_detector(model), max_people=max_people)
    frames = people = 0
    with open_source(f"video:{video}") as source:
        for frame in source:
            found = tracker.step({"cam": frame.image})["cam"]
            openpose_json.write_frame(openpose_json.frame_file(out, Path(video).stem, frame.index),
                                      [p.keypoints for p in found], frame.index, frame.capture_time_ns,
                                      tracker.model.layout)
            frames += 1
            people += len(found)
    return {"video": str(video), "frames": frames, "people": people, "detector_runs": tracker.counts.detector_runs,
            "out": str(out)}
