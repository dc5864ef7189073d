"""The edge detector on the real Balancing trial (mocap.io.demo_data.fetch_trial: Pose2Sim's
four 1080 x 1920 videos at 60 fps and the OpenPose BODY_25B detections shipped with them).

Accuracy: PCK against OpenPose on the 17 keypoints both layouts share (COCO order), with the
subject's box size — the larger side of the box around its OpenPose keypoints — as the
scale. The subject in OpenPose's files is its largest person (a second one stands in the
background of two cameras); ours is the largest person our tracker found (its own choice,
without looking at OpenPose). Throughput: frames per second per camera with region
tracking and packing, and naively (person detector + one landmark inference per frame).
Robustness: the same PCK under perturbations standing in for other CPUs' rounding
(`python -m mocap.cli.edge_robustness`).
"""

from __future__ import annotations

import copy
import time
import types
from pathlib import Path

import numpy as np
import onnxruntime as ort

from mocap.io import demo_data
from mocap_edge import camera_box, resources
from mocap_edge.detect.base import Detector, Person
from mocap_edge.detect.blazepose import BlazePose
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


def run(model: Detector, videos: dict[int, list[np.ndarray]], pack: bool = True, detect_every: tuple[int, int] = (1, 1),
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
        _, naive = run(whole_image(model), videos, pack=False, cameras_per_step=cams)
        _, packed = run(model, videos, pack=True, cameras_per_step=cams)
        per_process[cams] = {"fps_naive": naive["fps_per_camera"], "fps_packed": packed["fps_per_camera"],
                             "speedup": packed["fps_per_camera"] / naive["fps_per_camera"]}
    _, hs = run(model, videos, detect_every=(8, 2), cameras_per_step=4)
    return {"bench": "edge", **per_process[1], "cameras_per_process": per_process,
            "hs_fps_per_camera": hs["fps_per_camera"], "hs_inferred_fps_per_camera": hs["inferred_fps_per_camera"],
            "two_people": several_people(model, demo_data.fetch_multiperson()),
            "model": "BlazePose full (MediaPipe 0.10.14) on onnxruntime, 2 threads"}


def whole_image(model: BlazePose) -> BlazePose:
    """The model with its person detector on the whole image only: the naive baseline's (the
    detector on every frame, as such pipelines run it; tiles would multiply its cost by 4)."""
    whole = copy.copy(model)
    whole.tiled = False
    return whole


def several_people(model: Detector, trial: Path) -> dict:
    """The camera box's tracker as the box runs it (up to camera_box.MAX_PEOPLE people, the
    person detector looking for newcomers every camera_box.REDETECT_EVERY frames) on each video
    of Pose2Sim's multi-person trial (two people): frames per second per camera and the people
    found per frame, per camera and overall."""
    videos = load_trial(trial)
    people, elapsed = {}, 0.0
    for c, frames in videos.items():
        tracker = Tracker(model, max_people=camera_box.MAX_PEOPLE, redetect_every=camera_box.REDETECT_EVERY)
        start = time.perf_counter()
        people[c] = [len(tracker.step({c: image})[c]) for image in frames]
        elapsed += time.perf_counter() - start
    return {"fps_per_camera": sum(len(v) for v in videos.values()) / elapsed,
            "people_per_frame": float(np.mean([n for v in people.values() for n in v])),
            "people_per_frame_by_camera": {f"cam{c:02d}": round(float(np.mean(v)), 2) for c, v in people.items()},
            "people_in_view": 2}


def perturbed(model: BlazePose, seed: int = 0, relative: float = 0.0, grey_levels: int = 0,
              unoptimised: bool = False) -> BlazePose:
    """A copy of a BlazePose model standing in for another CPU's arithmetic: its landmark
    network's outputs times (1 + relative x N(0, 1)), its input crops plus uniform integer
    noise in [-grey_levels, grey_levels] grey levels, or (unoptimised) the network run by
    onnxruntime without graph optimisations (other kernels, other rounding: outputs differ by
    ~3e-6 relative). seed: the noise's."""
    rng = np.random.default_rng(seed)
    network = _unoptimised_landmarker() if unoptimised else model.landmarker

    def run(x: np.ndarray, outputs: list[str] | None = None) -> list[np.ndarray]:
        if grey_levels:
            x = np.clip(x + rng.integers(-grey_levels, grey_levels + 1, x.shape) / 255.0, 0.0, 1.0).astype(np.float32)
        out = network.run(x, outputs)
        return [o * (1 + relative * rng.standard_normal(o.shape)).astype(o.dtype) for o in out] if relative else out

    twin = copy.copy(model)
    twin.landmarker = types.SimpleNamespace(run=run)
    return twin


def _unoptimised_landmarker() -> object:
    """BlazePose's landmark network (the default model folder) without onnxruntime's graph
    optimisations (fused operators): the same weights through other kernels."""
    options = ort.SessionOptions()
    options.graph_optimization_level = ort.GraphOptimizationLevel.ORT_DISABLE_ALL
    options.intra_op_num_threads, options.inter_op_num_threads = 2, 1
    session = ort.InferenceSession(str(resources.models_dir("blazepose") / "pose_landmark_full.onnx"), options, providers=["CPUExecutionProvider"])
    name = session.get_inputs()[0].name
    return types.SimpleNamespace(run=lambda x, outputs=None: session.run(outputs, {name: x}))


def perturbations(seeds: int = 3, relative: float = 1e-4, grey_levels: int = 1) -> dict[str, dict]:
    """The runs of `robustness`, by name: the plain run, the unoptimised graph, and `seeds`
    seeds each of output noise and of input noise (options of `perturbed`)."""
    runs: dict[str, dict] = {"plain": {}, "unoptimised graph": {"unoptimised": True}}
    for s in range(1, seeds + 1):
        runs[f"outputs x (1 + {relative:g} N), seed {s}"] = {"seed": s, "relative": relative}
    for s in range(1, seeds + 1):
        runs[f"input +-{grey_levels} grey level, seed {s}"] = {"seed": s, "grey_levels": grey_levels}
    return runs


def robustness(trial: Path, seeds: int = 3, relative: float = 1e-4, grey_levels: int = 1,
               videos: dict[int, list[np.ndarray]] | None = None) -> dict:
    """PCK of the tracked pipeline on the plain run and under small perturbations that stand
    in for other CPUs (`perturbations`), and the spread (min, max) of each figure over the
    perturbed runs. About 30 s a run on 2 cores."""
    videos = videos or load_trial(trial)
    model = BlazePose()
    runs = {}
    for name, options in perturbations(seeds, relative, grey_levels).items():
        found, _ = run(perturbed(model, **options) if options else model, videos)
        runs[name] = pck(trial, found)
    return {"runs": runs, "spread": spread([r for n, r in runs.items() if n != "plain"])}


def spread(scores: list[dict]) -> dict:
    """[min, max] of PCK@0.05 and @0.10, overall and per camera, over results of `pck`."""
    def span(values: list[float]) -> list[float]:
        return [min(values), max(values)]

    keys = ("pck05", "pck10")
    cameras = scores[0]["per_camera"]
    return {**{k: span([s[k] for s in scores]) for k in keys},
            "per_camera": {c: {k: span([s["per_camera"][c][k] for s in scores]) for k in keys} for c in cameras}}
