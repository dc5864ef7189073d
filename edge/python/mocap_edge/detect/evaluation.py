"""The edge detector on the real Balancing trial (mocap.demo_data.fetch_trial: Pose2Sim's
four 1080 x 1920 videos at 60 fps and the OpenPose BODY_25B detections shipped with them).

Accuracy: PCK against OpenPose on the 17 keypoints both layouts share (COCO order), with the
subject's box size — the larger side of the box around its OpenPose keypoints — as the
scale. The subject in OpenPose's files is its largest person (a second one stands in the
background of two cameras); ours is the largest person our tracker found (its own choice,
without looking at OpenPose). Throughput: frames per second per camera with region
tracking and packing, and naively (person detector + one landmark inference per frame).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from mocap_edge.detect.blazepose import BlazePose, Person
from mocap_edge.detect.openpose_json import box_size, largest_people
from mocap_edge.detect.tracking import Tracker
from mocap_edge.sources.base import open_source

COCO_FROM_BLAZEPOSE = np.array([0, 2, 5, 7, 8, 11, 12, 13, 14, 15, 16, 23, 24, 25, 26, 27, 28])
CAMERAS = (1, 2, 3, 4)


def load_trial(trial: Path, cameras=CAMERAS, frames: int | None = None) -> dict[int, list[np.ndarray]]:
    """RGB frames of each camera's video."""
    out = {}
    for c in cameras:
        with open_source(f"video:{trial / 'videos' / f'cam0{c}.mp4'}") as source:
            out[c] = [f.image for _, f in zip(range(frames or 10**9), source)]
    return out


def openpose_subjects(trial: Path, camera: int) -> list[np.ndarray]:
    """(25, 3) per frame: the largest person of OpenPose's files of a camera (BODY_25B; its
    first 17 keypoints are COCO's)."""
    return largest_people(trial / "pose" / f"cam{camera}_json")


def subject(people: list[Person]) -> Person | None:
    return max(people, key=lambda p: p.next_roi.size) if people else None


def run(model: BlazePose, videos: dict[int, list[np.ndarray]], pack: bool = True, detect_every: tuple[int, int] = (1, 1),
        cameras_per_step: int = 1) -> tuple[dict[int, list], dict]:
    """Detections of every frame (None where not detected) and the throughput. cameras_per_step
    cameras share one tracker step (their crops in one inference); detect_every (period,
    burst): detection on `burst` consecutive frames of every `period` (the HS mode)."""
    period, burst = detect_every
    cams = list(videos)
    groups = [cams[i:i + cameras_per_step] for i in range(0, len(cams), cameras_per_step)]
    out: dict[int, list] = {c: [] for c in cams}
    inferred, counts = 0, []
    start = time.perf_counter()
    for group in groups:
        tracker = Tracker(model, pack=pack)
        for f in range(len(videos[group[0]])):
            if f % period >= burst:
                for c in group:
                    out[c].append(None)
                continue
            found = tracker.step({c: videos[c][f] for c in group})
            inferred += len(group)
            for c in group:
                out[c].append(subject(found[c]))
        counts.append(tracker.counts)
    elapsed = time.perf_counter() - start
    frames = sum(len(v) for v in videos.values())
    return out, {"fps_per_camera": frames / elapsed, "inferred_fps_per_camera": inferred / elapsed,
                 "detector_runs": sum(c.detector_runs for c in counts),
                 "landmark_batches": sum(c.landmark_batches for c in counts)}


def pck(trial: Path, detections: dict[int, list]) -> dict:
    """PCK@0.05 and @0.10 per camera and over all of them (module docstring)."""
    hits = {0.05: {}, 0.10: {}}
    for c, people in detections.items():
        for a in hits:
            hits[a][c] = []
        subjects = openpose_subjects(trial, c)
        for f, person in enumerate(people):
            truth = subjects[f][:17]
            seen, scale = truth[:, 2] > 0, box_size(truth)
            d = (np.full(17, np.inf) if person is None
                 else np.linalg.norm(person.keypoints[COCO_FROM_BLAZEPOSE, :2] - truth[:, :2], axis=1))
            for a in hits:
                hits[a][c] += list(d[seen] < a * scale)
    result = {f"pck{int(a * 100):02d}": float(np.mean(sum(v.values(), []))) for a, v in hits.items()}
    result["per_camera"] = {c: {f"pck{int(a * 100):02d}": float(np.mean(hits[a][c])) for a in hits} for c in detections}
    return result


def bench(trial: Path) -> dict:
    """Throughput per camera with and without tracking/packing, 1 and 4 cameras per
    process (one tracker step takes one frame of each), and in the HS mode (detections on 2
    of every 8 frames, 4 cameras)."""
    model = BlazePose()
    videos = load_trial(trial)
    per_process = {}
    for cams in (1, 4):
        _, naive = run(model, videos, pack=False, cameras_per_step=cams)
        _, packed = run(model, videos, pack=True, cameras_per_step=cams)
        per_process[cams] = {"fps_naive": naive["fps_per_camera"], "fps_packed": packed["fps_per_camera"],
                             "speedup": packed["fps_per_camera"] / naive["fps_per_camera"]}
    _, hs = run(model, videos, detect_every=(8, 2), cameras_per_step=4)
    return {"bench": "edge", **per_process[1], "cameras_per_process": per_process,
            "hs_fps_per_camera": hs["fps_per_camera"], "hs_inferred_fps_per_camera": hs["inferred_fps_per_camera"],
            "model": "BlazePose full (MediaPipe 0.10.14) on onnxruntime, 2 threads"}
