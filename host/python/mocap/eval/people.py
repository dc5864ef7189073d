"""`mocap eval --people N`: a scene of N performers (mocap.sim.people) solved by the host's
SubjectTracker from every camera's people, in the order each camera lists them, and scored
per performer against the truth; each performer is also solved alone (the same clip, place,
suit and cameras, nobody else on the stage) to compare with.

Video only: every subject is solved with the default skeleton and the layout on it (which
subject wears which suit is not decided yet), alone as together; errors are over the 13
anatomical joint centres (mocap.model.joint_centres), which every skeleton agrees on.
Scoring, per frame: the subjects tracked are matched to the performers by the least total
mean joint-centre distance, a pair made only within MATCH_M; a performer's identity swaps
are the times the subject matched to it changes id.
"""

from __future__ import annotations

import itertools
import time as _time
from pathlib import Path

import numpy as np

from mocap import _core, paths
from mocap.model import joint_centres
from mocap.model import prior as pose_prior
from mocap.sim import people as sim_people
from mocap.sim.take import Config

MATCH_M = 0.5  # a subject further than this from a performer (mean joint centre) is not them


def nominal(layout_name: str) -> tuple[_core.Skeleton, _core.KeypointLayout]:
    """The skeleton every subject is solved with, and the layout on it."""
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / f"{layout_name}.json"), skeleton).scaled_to(skeleton)
    return skeleton, layout


def track(scene: sim_people.Scene, tracking: _core.TrackerOptions | None = None,
          wall_ms: list | None = None) -> tuple[list[dict], dict]:
    """Per frame the subjects tracked ({id: (theta, cameras)}), and the tracker's counts;
    wall_ms, when given, receives each frame's SubjectTracker.track time."""
    first = scene.performers[0]
    skeleton, layout = nominal(first.layout.name)
    tracker = _core.SubjectTracker(skeleton, first.rig, layout, pose_prior.load(), _core.SolverOptions(),
                                   tracking or _core.TrackerOptions())
    frames = []
    for time, seen in zip(first.times, scene.persons):
        cameras = [c for c, people in enumerate(seen or []) for _ in people]
        keypoints = np.array([p for people in (seen or []) for p in people]).reshape(len(cameras), len(layout), 3)
        start = _time.perf_counter()
        subjects, _ = tracker.track(float(time), cameras, keypoints)
        if wall_ms is not None:
            wall_ms.append(1e3 * (_time.perf_counter() - start))
        frames.append({s.id: (np.array(s.result.theta), list(s.cameras)) for s in subjects})
    return frames, tracker.counts


def _centres(skeleton: _core.Skeleton, theta: np.ndarray) -> np.ndarray:
    return skeleton.forward_kinematics(theta)[1][joint_centres.bone_indices(skeleton.bone_names)]


def _match(distance: np.ndarray) -> dict[int, int]:
    """Performer -> subject column of the least total distance, pairs within MATCH_M only."""
    n_perf, n_subj = distance.shape
    best, best_cost = {}, (0, 0.0)
    for k in range(min(n_perf, n_subj), 0, -1):
        for perf in itertools.combinations(range(n_perf), k):
            for subj in itertools.permutations(range(n_subj), k):
                d = distance[list(perf), list(subj)]
                if (d > MATCH_M).any():
                    continue
                cost = (-k, float(d.sum()))  # the most pairs, then the least distance
                if not best or cost < best_cost:
                    best, best_cost = dict(zip(perf, subj)), cost
        if best:
            return best
    return best


def score(scene: sim_people.Scene, frames: list[dict]) -> list[dict]:
    """Per performer: frames matched to a subject, their mean joint-centre error (cm), and
    the identity swaps."""
    skeleton, _ = nominal(scene.performers[0].layout.name)
    truth = [[_centres(t.skeleton, th) for th in t.thetas] for t in scene.performers]
    errors = [[] for _ in scene.performers]
    ids = [[] for _ in scene.performers]
    for f, subjects in enumerate(frames):
        seen = {i: _centres(skeleton, theta) for i, (theta, cameras) in subjects.items() if cameras}
        order = list(seen)
        distance = np.array([[np.linalg.norm(seen[i] - truth[p][f], axis=1).mean() for i in order]
                             for p in range(len(truth))]).reshape(len(truth), len(order))
        for p, s in _match(distance).items():
            errors[p].append(distance[p, s])
            ids[p].append(order[s])
    out = []
    for p, (e, i) in enumerate(zip(errors, ids)):
        out.append({"frames": len(frames), "frames_tracked": len(e),
                    "joint_centres_pos_cm": round(100.0 * float(np.mean(e)), 2) if e else None,
                    "identity_swaps": int(np.count_nonzero(np.diff(i))) if len(i) > 1 else 0,
                    "ids": sorted(set(i))})
    return out


def closest_approach(scene: sim_people.Scene) -> float | None:
    """The least floor distance between two performers' roots over the scene, m."""
    roots = np.array([t.thetas[:, :2] for t in scene.performers])  # (P, F, 2)
    pairs = [np.linalg.norm(roots[a] - roots[b], axis=1).min() for a, b in itertools.combinations(range(len(roots)), 2)]
    return round(float(min(pairs)), 3) if pairs else None


def evaluate(clips: list[Path], people: int, seconds: float, config: Config, seed: int) -> dict:
    """The scene of `people` performers, tracked and scored, and each performer alone."""
    scene = sim_people.simulate(clips, people, seconds, config, np.random.default_rng(seed))
    frames, counts = track(scene)
    together = score(scene, frames)
    for p, result in enumerate(together):
        alone_scene = sim_people.simulate(clips, people, seconds, config, np.random.default_rng(seed), alone=p)
        alone = score(alone_scene, track(alone_scene)[0])[0]
        result["clip"] = Path(clips[scene.placements[p].clip]).name
        result["alone_joint_centres_pos_cm"] = alone["joint_centres_pos_cm"]
        if result["joint_centres_pos_cm"] and alone["joint_centres_pos_cm"]:
            result["ratio_to_alone"] = round(result["joint_centres_pos_cm"] / alone["joint_centres_pos_cm"], 3)
    return {"people": people, "seconds": seconds, "seed": seed, "preset": config.preset,
            "frames": len(frames), "closest_approach_m": closest_approach(scene),
            "identity_swaps": sum(r["identity_swaps"] for r in together),
            "subjects_born": counts["births"], "tracker": counts, "performers": together}


BENCH_CLIPS = ("cmu-131/131_01.bvh", "cmu-131/131_02.bvh", "cmu-131/131_03.bvh")  # test split, 8-10 s each


def bench(seconds: float = 8.0, seed: int = 0) -> dict:
    """`make bench`'s multi line: the host's solve of 3 people seen by 8 cameras (the
    SubjectTracker's whole frame: assignment, births, the solves) per frame, wall time, with
    the solves on both cores and on one."""
    clips = [paths.shared_file(f"data/mocap/{c}") for c in BENCH_CLIPS]
    scene = sim_people.simulate(clips, 3, seconds, Config(preset="hq13"), np.random.default_rng(seed))
    out = {"bench": "multi", "people": 3, "cameras": len(scene.performers[0].rig.cameras),
           "frames": len(scene.persons)}
    for threads in (2, 1):
        tracking = _core.TrackerOptions()
        tracking.threads = threads
        ms: list[float] = []
        frames, counts = track(scene, tracking, ms)
        tracked = np.array(ms[len(ms) // 10:])  # the subjects are born in the first frames
        key = f"threads_{threads}"
        out[key] = {"p50_ms": round(float(np.median(tracked)), 3), "p99_ms": round(float(np.percentile(tracked, 99)), 3),
                    "max_ms": round(float(tracked.max()), 3), "subjects_born": counts["births"],
                    "identity_swaps": sum(r["identity_swaps"] for r in score(scene, frames))}
    out["target_p99_ms"] = 10.0
    return out
