"""`mocap eval --people N`: a scene of N performers (mocap.sim.people) solved by the host's
SubjectTracker from every camera's people, in the order each camera lists them, and scored
per performer against the truth; each performer is also solved alone (the same clip, place,
suit and cameras, nobody else on the stage) to compare with.

Each performer wears a suit of IMUs of their own, calibrated (the oracle calibration: their
skeleton, the layout on it, the sensors' true sites), which the tracker finds on them from
motion; until then a subject is solved from video with the skeleton and layout of the suit
leading for it (the default ones before any does, and always without suits, `suits=False`).
Errors are over the 13 anatomical joint centres
(mocap.model.joint_centres), which every skeleton agrees on.
Scoring, per frame: the subjects tracked are matched to the performers by the least total
mean joint-centre distance, a pair made only within MATCH_M; a performer's identity swaps
are the times the subject matched to it changes id.
"""

from __future__ import annotations

import itertools
import json
import time as _time
from pathlib import Path

import numpy as np

from mocap import _core, paths
from mocap.io.session import Session
from mocap.model import joint_centres
from mocap.model import prior as pose_prior
from mocap.model.solver import imu_set_json
from mocap.net import wire
from mocap.recording import offline
from mocap.sim import messages as sim_messages
from mocap.sim import people as sim_people
from mocap.sim.take import Config

MATCH_M = 0.5  # a subject further than this from a performer (mean joint centre) is not them


def nominal(layout_name: str) -> tuple[_core.Skeleton, _core.KeypointLayout]:
    """The skeleton every subject is solved with, and the layout on it."""
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / f"{layout_name}.json"), skeleton).scaled_to(skeleton)
    return skeleton, layout


def worn_by(scene: sim_people.Scene, swap_at_s: float | None = None) -> np.ndarray:
    """(F, performers): who wears each suit on each frame: its own performer, except that
    performers 0 and 1 wear each other's from swap_at_s (s into the scene) on."""
    t = scene.performers[0].times - scene.performers[0].times[0]
    out = np.tile(np.arange(len(scene.performers)), (len(t), 1))
    if swap_at_s is not None:
        out[t >= swap_at_s, :2] = [1, 0]
    return out


def run_tracker(scene: sim_people.Scene, suits: bool = True, tracking: _core.TrackerOptions | None = None,
                wall_ms: list | None = None, worn: np.ndarray | None = None) -> tuple[_core.SubjectTracker, list]:
    """The scene through a SubjectTracker of the nominal skeleton: the tracker and every frame's
    SubjectFrames. suits: each performer has a suit calibrated on them (the oracle calibration:
    their skeleton, the layout on it, the true sensor sites), worn as `worn` says (worn_by;
    default their own); wall_ms, when given, receives each frame's track time."""
    first = scene.performers[0]
    skeleton, layout = nominal(first.layout.name)
    calibrations = [(t.skeleton, t.layout, t.imus) for t in scene.performers] if suits else []
    tracker = _core.SubjectTracker(skeleton, first.rig, layout, pose_prior.load(), _core.SolverOptions(),
                                   tracking or _core.TrackerOptions(), calibrations)
    worn = worn_by(scene) if worn is None else worn
    frames = []
    for f, (time, seen) in enumerate(zip(first.times, scene.persons)):
        cameras = [c for c, people in enumerate(seen or []) for _ in people]
        keypoints = np.array([p for people in (seen or []) for p in people]).reshape(len(cameras), len(layout), 3)
        wearers = [scene.performers[p] for p in worn[f]] if suits else []
        quaternions, accelerations = [t.quaternions[f] for t in wearers], [t.accelerations[f] for t in wearers]
        start = _time.perf_counter()
        subjects, _ = tracker.track(float(time), cameras, keypoints, quaternions, accelerations)
        if wall_ms is not None:
            wall_ms.append(1e3 * (_time.perf_counter() - start))
        frames.append(subjects)
    return tracker, frames


def track(scene: sim_people.Scene, suits: bool = True, tracking: _core.TrackerOptions | None = None,
          wall_ms: list | None = None, worn: np.ndarray | None = None) -> tuple[list[dict], dict]:
    """Per frame the subjects tracked ({id: (centres, cameras, suit)}: the solved joint centres
    (J, 3), through the skeleton the solve had; suit, the performer whose suit's readings the
    solve had, -1 for none), and the tracker's counts (run_tracker says the rest)."""
    tracker, per_frame = run_tracker(scene, suits, tracking, wall_ms, worn)
    default, _ = nominal(scene.performers[0].layout.name)
    frames = [{s.id: (_centres(scene.performers[s.skeleton].skeleton if s.skeleton >= 0 else default,
                               np.array(s.result.theta)), list(s.cameras), s.suit) for s in subjects}
              for subjects in per_frame]
    return frames, tracker.counts


def write_session(scene: sim_people.Scene, folder: Path, suits: bool, inputs: list[str], output: str) -> Path:
    """A session of as many people as the scene has, in `folder` (the default skeleton, the
    told rig, the scene's layout; suits: each performer's suit, its sensors "pP_NAME" with
    their oracle calibration on the performer's skeleton)."""
    first = scene.performers[0]
    skeleton, _ = nominal(first.layout.name)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "skeleton.json").write_text(skeleton.to_json())
    (folder / "rig.json").write_text(first.rig.to_json())
    worn, every = [], []
    for p, t in enumerate(scene.performers if suits else []):
        sites = [_renamed(s, sim_messages.suit_sensor(p, s.name)) for s in t.imus]
        (folder / f"suit{p}_skeleton.json").write_text(t.skeleton.to_json())
        (folder / f"suit{p}_imus.json").write_text(json.dumps(imu_set_json(t.skeleton, sites)))
        worn.append({"imus": f"suit{p}_imus.json", "skeleton": f"suit{p}_skeleton.json"})
        every += [_renamed(s, s.name) for s in sites]
    (folder / "imus.json").write_text(json.dumps(imu_set_json(skeleton, every)))
    session = Session("skeleton.json", "rig.json", str(paths.LAYOUTS / f"{first.layout.name}.json"), "imus.json",
                      inputs, output, prior=str(paths.HOST_DATA / "prior_default.json"),
                      people=len(scene.performers), suits=worn, base=folder)
    return session.save(folder / "session.json")


def by_frame(scene: sim_people.Scene, poses: list, offset_ns: int = 0) -> list[dict]:
    """PoseFrames of the scene (capture times moved by offset_ns) as track() gives frames:
    {subject_id: (centres, cameras, suit)}, the centres of the PoseFrame's joints, suit the
    performer whose suit's sensors it lists."""
    index = {t + offset_ns: f for f, t in enumerate(sim_messages.frame_times_ns(scene.performers[0]))}
    frames: list[dict] = [{} for _ in scene.persons]
    for pose in poses:
        if pose.capture_time_ns in index:
            suit = sim_messages.suit_of_sensor(pose.imus[0]) if pose.imus else -1
            joints = {j.name: (j.px, j.py, j.pz) for j in pose.joints}
            centres = np.array([joints[b] for b in joint_centres.JOINTS.values()])
            frames[index[pose.capture_time_ns]][pose.subject_id] = (centres, list(pose.cameras), suit)
    return frames


def solve_as_mocapd(scene: sim_people.Scene, folder: Path, suits: bool = False) -> tuple[list[dict], object]:
    """The scene's messages (every person each camera found; suits: each performer's suit's
    batches) solved by the live host's pipeline (what mocapd runs) in one process, a session
    of write_session: its frames as by_frame gives them, and the host's last Health."""
    pipeline = offline.pipeline_for(write_session(scene, folder, suits, ["scene"], "scene"))
    poses = offline.solve_messages(pipeline, sim_messages.scene_messages(scene, suits))
    last_ns = sim_messages.frame_times_ns(scene.performers[0])[-1]
    return by_frame(scene, poses), wire.Health.FromString(pipeline.health(last_ns))


def _renamed(site: _core.ImuSite, name: str) -> _core.ImuSite:
    out = _core.ImuSite()
    out.name, out.bone, out.mount, out.offset, out.reference = name, site.bone, site.mount, site.offset, site.reference
    return out


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


def score(scene: sim_people.Scene, frames: list[dict], worn: np.ndarray | None = None) -> list[dict]:
    """Per performer: frames matched to a subject, their mean joint-centre error (cm), the
    identity swaps, and which suit the matched subject's solve had: the one they wear (worn:
    worn_by) from which second on, and on how many frames another one."""
    worn = worn_by(scene) if worn is None else worn
    truth = [[_centres(t.skeleton, th) for th in t.thetas] for t in scene.performers]
    matched = [[] for _ in scene.performers]  # per performer: (frame, error m, id, suit)
    for f, subjects in enumerate(frames):
        seen = {i: (centres, suit) for i, (centres, cameras, suit) in subjects.items() if cameras}
        order = list(seen)
        distance = np.array([[np.linalg.norm(seen[i][0] - truth[p][f], axis=1).mean() for i in order]
                             for p in range(len(truth))]).reshape(len(truth), len(order))
        for p, s in _match(distance).items():
            matched[p].append((f, distance[p, s], order[s], seen[order[s]][1]))
    times = scene.performers[0].times
    out = []
    for p, rows in enumerate(matched):
        ids = [r[2] for r in rows]
        own = [r[0] for r in rows if r[3] >= 0 and worn[r[0], r[3]] == p]
        out.append({"frames": len(frames), "frames_tracked": len(rows),
                    "joint_centres_pos_cm": round(100.0 * float(np.mean([r[1] for r in rows])), 2) if rows else None,
                    "joint_centres_pos_cm_by_second": _by_second(times - times[0], rows),
                    "identity_swaps": int(np.count_nonzero(np.diff(ids))) if len(ids) > 1 else 0,
                    "ids": sorted(set(ids)),
                    "own_suit_from_s": round(float(times[own[0]] - times[0]), 2) if own else None,
                    "frames_with_own_suit": len(own),
                    "frames_with_another_suit": sum(1 for r in rows if r[3] >= 0 and worn[r[0], r[3]] != p),
                    "own_suit_frames": own})
    return out


def _by_second(times: np.ndarray, rows: list) -> list:
    """The mean error (cm) of the matched frames (rows: (frame, error m, ...)) in each second of
    the scene, None for a second without any."""
    seconds = [[] for _ in range(int(times[-1]) + 1)]
    for row in rows:
        seconds[int(times[row[0]])].append(row[1])
    return [round(100.0 * float(np.mean(e)), 2) if e else None for e in seconds]


def closest_approach(scene: sim_people.Scene) -> float | None:
    """The least floor distance between two performers' roots over the scene, m."""
    roots = np.array([t.thetas[:, :2] for t in scene.performers])  # (P, F, 2)
    pairs = [np.linalg.norm(roots[a] - roots[b], axis=1).min() for a, b in itertools.combinations(range(len(roots)), 2)]
    return round(float(min(pairs)), 3) if pairs else None


def evaluate(clips: list[Path], people: int, seconds: float, config: Config, seed: int, suits: bool = True,
             swap_suits_at_s: float | None = None) -> dict:
    """The scene of `people` performers, tracked and scored, and each performer alone;
    suits: each wears their own (else video only), performers 0 and 1 swapping theirs at
    swap_suits_at_s (s into the scene) if given."""
    scene = sim_people.simulate(clips, people, seconds, config, np.random.default_rng(seed))
    worn = worn_by(scene, swap_suits_at_s)
    frames, counts = track(scene, suits, worn=worn)
    together = score(scene, frames, worn)
    times = scene.performers[0].times - scene.performers[0].times[0]
    for p, result in enumerate(together):
        alone_scene = sim_people.simulate(clips, people, seconds, config, np.random.default_rng(seed), alone=p)
        alone = score(alone_scene, track(alone_scene, suits)[0])[0]
        result["clip"] = Path(clips[scene.placements[p].clip]).name
        result["alone_joint_centres_pos_cm"] = alone["joint_centres_pos_cm"]
        result["alone_joint_centres_pos_cm_by_second"] = alone["joint_centres_pos_cm_by_second"]
        if result["joint_centres_pos_cm"] and alone["joint_centres_pos_cm"]:
            result["ratio_to_alone"] = round(result["joint_centres_pos_cm"] / alone["joint_centres_pos_cm"], 3)
        own = result.pop("own_suit_frames")
        if swap_suits_at_s is not None and p < 2:  # when the suit now worn was found on them
            after = [f for f in own if times[f] >= swap_suits_at_s]
            result["swapped_suit_found_after_s"] = round(float(times[after[0]] - swap_suits_at_s), 2) if after else None
    return {"people": people, "seconds": seconds, "seed": seed, "preset": config.preset, "suits": suits,
            "swap_suits_at_s": swap_suits_at_s, "frames": len(frames), "closest_approach_m": closest_approach(scene),
            "identity_swaps": sum(r["identity_swaps"] for r in together), "suit_changes": counts["suit_changes"],
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
        frames, counts = track(scene, True, tracking, ms)
        tracked = np.array(ms[len(ms) // 10:])  # the subjects are born in the first frames
        key = f"threads_{threads}"
        out[key] = {"p50_ms": round(float(np.median(tracked)), 3), "p99_ms": round(float(np.percentile(tracked, 99)), 3),
                    "max_ms": round(float(tracked.max()), 3), "subjects_born": counts["births"],
                    "identity_swaps": sum(r["identity_swaps"] for r in score(scene, frames)),
                    "suits_worn_at_end": sum(1 for _, _, suit in frames[-1].values() if suit >= 0)}
    out["target_p99_ms"] = 10.0
    return out
