"""Several people on real video: Pose2Sim's multi-person demo trial (pose2sim 0.10.49,
Demo_MultiPerson: four cameras, 100 frames at 60 fps, two people, Qualisys calibration;
`mocap.io.demo_data.fetch_multiperson`). Every video is detected by the camera box's own
detector (BlazePose with region tracking, up to MAX_PEOPLE per camera, the person detector
looking for newcomers every REDETECT_EVERY frames), each camera's people
listed in its own order, and the host's SubjectTracker tracks and solves them from video (the
default skeleton). No ground truth: scored by what a user sees — the people per frame, the
subjects born, the ids each lasting through the trial, and the reprojection error of each
subject's solved keypoints against the detections assigned to it. The contact sheet draws,
on frames of every camera, each detection in the colour of the subject it was assigned to,
with its id.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from mocap import _core
from mocap.eval import people as sim_scene
from mocap.io import demo_data
from mocap.io.video_rig import rig_for
from mocap.model import prior as pose_prior
from mocap.model import studio
from mocap_edge.detect.base import open_detector
from mocap_edge.detect.tracking import Tracker
from mocap_edge.detect.video import detect_frames

MAX_PEOPLE = 4  # tracked per camera by the detector
REDETECT_EVERY = 4  # frames: the person detector looks for newcomers (Pose2Sim's demo: det_frequency 4)
COLOURS = [(230, 25, 75), (60, 180, 75), (0, 130, 200), (245, 130, 48), (145, 30, 180), (70, 240, 240)]  # RGB


def detect(trial: Path) -> tuple[_core.Rig, str, float, list, list]:
    """The rig, the detector's layout, the frame rate, per frame per camera the people found
    ((K, 3) each), and per camera its frames' images (RGB, for the contact sheet)."""
    files = sorted((trial / "videos").glob("*.mp4"))
    rig = rig_for(next((trial / "calibration").glob("*.qca.txt")), [v.stem for v in files])
    model = open_detector("blazepose", threads=2)
    found, images, rate = [], [], 60.0
    for video in files:
        tracker = Tracker(model, max_people=MAX_PEOPLE, redetect_every=REDETECT_EVERY)
        frames = list(detect_frames(video, tracker))
        found.append([people for _, people, _ in frames])
        images.append([frame.image for frame, _, _ in frames])
        rate = frames[0][2]
    n = min(len(f) for f in found)
    per_frame = [[found[c][f] for c in range(len(files))] for f in range(n)]
    return rig, model.layout.name, float(rate), per_frame, images


def track(rig: _core.Rig, layout_name: str, rate: float, per_frame: list) -> tuple[list, list, dict]:
    """Per frame: the subjects ({id: theta}) and per camera the id each person was assigned
    (0: none); the tracker's counts."""
    skeleton, layout = sim_scene.nominal(layout_name)
    tracker = _core.SubjectTracker(skeleton, rig, layout, pose_prior.load())
    subjects, assigned = [], []
    for f, seen in enumerate(per_frame):
        cameras = [c for c, people in enumerate(seen) for _ in people]
        keypoints = np.array([p for people in seen for p in people]).reshape(len(cameras), len(layout), 3)
        frame, ids = tracker.track(f / rate, cameras, keypoints)
        subjects.append({s.id: np.array(s.result.theta) for s in frame if s.cameras})
        split, i = [], 0
        for people in seen:
            split.append(list(ids[i:i + len(people)]))
            i += len(people)
        assigned.append(split)
    return subjects, assigned, tracker.counts


def reprojection_px(rig: _core.Rig, layout_name: str, per_frame: list, subjects: list, assigned: list) -> list:
    """Per assigned detection: the median pixel distance between its confident keypoints and
    its subject's solved sites projected into its camera."""
    skeleton, layout = sim_scene.nominal(layout_name)
    out = []
    for seen, solved, ids in zip(per_frame, subjects, assigned):
        points = {i: studio.site_positions(skeleton, layout.bones, layout.offsets, theta) for i, theta in solved.items()}
        for c, (people, people_ids) in enumerate(zip(seen, ids)):
            for person, i in zip(people, people_ids):
                if i not in points:
                    continue
                px, ok = rig.cameras[c].project(points[i])
                keep = ok & (person[:, 2] > 0.3)
                if keep.sum() >= 6:
                    out.append(float(np.median(np.linalg.norm(px[keep] - person[keep, :2], axis=1))))
    return out


def contact_sheet(images: list, per_frame: list, assigned: list, out: Path, frames: int = 5) -> None:
    """A grid: a row per camera, `frames` frames across the trial, each detection's keypoints
    in its subject's colour with the id written beside the head."""
    picks = np.linspace(10, len(per_frame) - 1, frames).round().astype(int)  # ids are born by frame 5
    rows = []
    for c in range(len(images)):
        tiles = []
        for f in picks:
            tile = images[c][f].copy()
            for person, i in zip(per_frame[f][c], assigned[f][c]):
                colour = COLOURS[(i - 1) % len(COLOURS)] if i else (200, 200, 200)
                for x, y, conf in person:
                    if conf > 0.3:
                        cv2.circle(tile, (int(x), int(y)), 16, colour, -1)
                head = person[0]
                cv2.putText(tile, str(i) if i else "-", (int(head[0]) + 40, int(head[1]) - 60),
                            cv2.FONT_HERSHEY_SIMPLEX, 7.0, colour, 22)
            cv2.putText(tile, f"cam{c + 1} frame {f}", (30, 140), cv2.FONT_HERSHEY_SIMPLEX, 4.0, (255, 255, 255), 10)
            tiles.append(cv2.resize(tile, (tile.shape[1] // 7, tile.shape[0] // 7), interpolation=cv2.INTER_AREA))
        rows.append(np.hstack(tiles))
    out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(out), cv2.cvtColor(np.vstack(rows), cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 80])


def evaluate(sheet: Path | None = None, trial: Path | None = None) -> dict:
    """The trial detected, tracked and scored; the contact sheet written to `sheet` if given."""
    trial = trial or demo_data.fetch_multiperson()
    rig, layout_name, rate, per_frame, images = detect(trial)
    subjects, assigned, counts = track(rig, layout_name, rate, per_frame)
    if sheet is not None:
        contact_sheet(images, per_frame, assigned, sheet)
    ids = sorted({i for frame in subjects for i in frame})
    spans = {i: [f for f, frame in enumerate(subjects) if i in frame] for i in ids}
    errors = reprojection_px(rig, layout_name, per_frame, subjects, assigned)
    detections = [sum(len(p) for p in seen) for seen in per_frame]
    return {"trial": "Demo_MultiPerson", "frames": len(per_frame), "cameras": len(rig.cameras),
            "people_per_camera_frame": round(float(np.mean(detections)) / len(rig.cameras), 2),
            "people_per_frame_by_camera": [round(float(np.mean([len(seen[c]) for seen in per_frame])), 2)
                                           for c in range(len(rig.cameras))],
            "subjects_born": counts["births"], "retired": counts["retired"], "revivals": counts["revivals"],
            "ids": {str(i): {"first_frame": s[0], "last_frame": s[-1], "frames": len(s)} for i, s in spans.items()},
            "subjects_per_frame": round(float(np.mean([len(s) for s in subjects])), 2),
            "assigned_share": round(float(np.mean([i > 0 for frame in assigned for cam in frame for i in cam])), 3),
            "reprojection_px_median": round(float(np.median(errors)), 1) if errors else None,
            "reprojection_px_p90": round(float(np.percentile(errors, 90)), 1) if errors else None,
            "tracker": counts}
