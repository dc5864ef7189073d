"""Several performers on one simulated stage, as a studio films a scene: each plays a clip of
their own (their own skeleton and suit of IMUs), placed on the floor with a heading and a start
time in the clip, and all are seen by the same cameras. A performer hides the others'
keypoints from a camera wherever they stand between them. Each camera's frame lists the
people its detector finds in an order of its own (a detector knows no identities); the truth
keeps who is who, to score an association against.

Placement: the performers' mean positions on a ring round the stage centre, neighbours
SPACING_M apart; headings spread over half a turn, so that the paths of walking clips cross
near the middle; fewer clips than performers: a clip is used again from another start time.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from mocap import _core, rotations
from mocap.io import retarget
from mocap.model import studio
from mocap.sim import detector, occlusion
from mocap.sim.take import Config, Take, camera_rig, frame_times, imu_readings, perturbed_rig, performer, preset_of

SPACING_M = 1.2  # between neighbouring performers' mean positions
MIN_SEEN = 6  # keypoints in view for a camera's detector to find a person
RING_MARGIN_M = 2.0  # between the cameras and the farthest a performer goes from the stage centre


@dataclasses.dataclass(frozen=True)
class Placement:
    clip: int  # index into the clips
    start_s: float  # into the clip
    heading_deg: float  # turn about the vertical, about the clip's mean position
    centre: tuple[float, float]  # where the clip's mean position goes on the floor, m


@dataclasses.dataclass
class Scene:
    performers: list[Take]  # each: placed truth, suit and readings, and their detections in the scene
    placements: list[Placement]
    persons: list  # per frame: None (no detection: high-speed mode) or per camera the (K, 3) people found
    who: list  # per frame: None or per camera the performer each of those people is


def placements(lengths: list[float], people: int, seconds: float, rng: np.random.Generator) -> list[Placement]:
    """Where and from when each of `people` performers plays, the clips (of `lengths` s) taken
    in turn."""
    radius = 0.0 if people == 1 else SPACING_M / (2.0 * np.sin(np.pi / people))
    out = []
    for i in range(people):
        clip = i % len(lengths)
        spare = max(lengths[clip] - seconds, 0.0)
        start = 0.0 if i < len(lengths) else float(rng.uniform(0.0, spare))
        angle = 2.0 * np.pi * i / people
        out.append(Placement(clip, start, 180.0 * i / people + float(rng.uniform(-15.0, 15.0)),
                             (radius * np.cos(angle), radius * np.sin(angle))))
    return out


def place(thetas: np.ndarray, heading_deg: float, centre: tuple[float, float]) -> np.ndarray:
    """(F, 66) poses turned by heading_deg about the vertical through their mean position and
    moved so that it stands at centre (the heights kept)."""
    turn = rotations.exp(np.array([0.0, 0.0, np.radians(heading_deg)]))
    out = thetas.copy()
    mean = thetas[:, :2].mean(axis=0)
    out[:, :2] = (thetas[:, :2] - mean) @ turn[:2, :2].T + centre
    out[:, 3:6] = rotations.log(turn @ rotations.exp(thetas[:, 3:6]))
    return out


def _performers(clips: list[Path], people: int, seconds: float, config: Config, rng):
    """Per performer: (skeleton, placed poses, dt, placement); every motion cut to the shortest."""
    loaded = [retarget.load_clip(c, config.rate) for c in clips]
    chosen = placements([(len(th) - 1) * dt for _, th, dt in loaded], people, seconds, rng)
    slices = []
    for p in chosen:
        _, thetas, dt = loaded[p.clip]
        first = int(round(p.start_s / dt))
        slices.append(thetas[first:first + int(round(seconds / dt)) + 1])
    n = min(len(s) for s in slices)
    out = []
    for p, motion in zip(chosen, slices):
        mapping, _, dt = loaded[p.clip]
        skeleton = _core.Skeleton.from_bones(retarget.BONES, mapping.parents, mapping.offsets)
        out.append((skeleton, place(motion[:n], p.heading_deg, p.centre), dt, p))
    return out


def simulate(clips: list[Path], people: int, seconds: float, config: Config, rng: np.random.Generator,
             alone: int | None = None) -> Scene:
    """A scene of `people` performers playing `clips` for `seconds` (less when the clips are
    shorter) before config's cameras (the preset's count or config.cameras, on a ring
    RING_MARGIN_M beyond the farthest performer), each with config's suit and errors.
    alone: only that performer on the stage (the same place, suit and cameras as in the
    scene of all), to compare with."""
    if people < 1 or not clips:
        raise ValueError(f"a scene needs a clip and at least one performer, not {len(clips)} clips for {people}")
    if alone is not None and not 0 <= alone < people:
        raise ValueError(f"performer {alone} is not one of the {people}")
    chosen = _performers(clips, people, seconds, config, rng)
    suits = [performer(skeleton, config, rng) for skeleton, _, _, _ in chosen]
    roots = np.concatenate([m[:, :3] for _, m, _, _ in chosen])
    reach = np.linalg.norm(roots[:, :2] - roots[:, :2].mean(axis=0), axis=1).max()
    n_cameras = config.cameras or preset_of(config).cameras
    true_rig = camera_rig(n_cameras, roots, radius=max(4.5, reach + RING_MARGIN_M))
    told_rig = perturbed_rig(camera_rig(n_cameras, roots, radius=max(4.5, reach + RING_MARGIN_M)),
                             config.camera_rotation_deg, config.camera_shift_m, rng)
    if alone is not None:
        chosen, suits = [chosen[alone]], [suits[alone]]
    dt = chosen[0][2]
    true_times, times = frame_times(len(chosen[0][1]), dt, config, rng)
    persons, who, own = _detections(chosen, suits, true_rig, config, rng)
    takes = []
    for (skeleton, motion, _, _), (layout, sites, imus), keypoints in zip(chosen, suits, own):
        quats, accs = imu_readings(skeleton, imus, motion, true_times, config, rng)
        takes.append(Take(skeleton, layout, imus, told_rig, true_rig, motion, times, keypoints, quats, accs, sites))
    return Scene(takes, [p for _, _, _, p in chosen], persons, who)


def _detections(chosen, suits, rig: _core.Rig, config: Config, rng) -> tuple[list, list, list]:
    """Per frame: the people each camera finds (detections, who) and each performer's own
    (C, K, 3) detections (zeros where a camera did not find them); None on skipped frames."""
    preset = preset_of(config)
    centres = np.array([c.center() for c in rig.cameras])
    caps = [occlusion.capsules(s.bone_names, s.parents) for s, _, _, _ in chosen]
    twins = [detector.mirror(layout.names) for layout, _, _ in suits]
    persons, who, own = [], [], [[] for _ in chosen]
    for f in range(len(chosen[0][1])):
        if f % preset.period >= preset.burst:
            for out in (persons, who, *own):
                out.append(None)
            continue
        bodies = [s.forward_kinematics(m[f]) for s, m, _, _ in chosen]
        capsules = [occlusion.segments(rot, pos, c) for (rot, pos), c in zip(bodies, caps)]
        found = [[] for _ in rig.cameras]
        for p, ((skeleton, motion, _, _), (layout, sites, _)) in enumerate(zip(chosen, suits)):
            others = tuple(np.concatenate([c[i] for q, c in enumerate(capsules) if q != p]) for i in range(3)) \
                if len(chosen) > 1 else None
            points = studio.site_positions(skeleton, layout.bones, sites, motion[f])
            hidden = occlusion.hidden(centres, points, np.asarray(layout.bones), *bodies[p], caps[p],
                                      skeleton.parents, others)
            frame = np.zeros((len(rig.cameras), len(layout), 3))
            for c, cam in enumerate(rig.cameras):
                px, ok = cam.project(points)
                if (ok & ~hidden[c]).sum() < MIN_SEEN:
                    continue
                det = detector.detect(np.nan_to_num(px), ok & ~hidden[c], twins[p], (cam.width, cam.height),
                                      config.detector, rng)
                if (det[:, 2] > 0).sum() >= MIN_SEEN:
                    frame[c] = det
                    found[c].append((p, det))
            own[p].append(frame)
        order = [rng.permutation(len(seen)) for seen in found]
        persons.append([[seen[i][1] for i in o] for seen, o in zip(found, order)])
        who.append([[seen[i][0] for i in o] for seen, o in zip(found, order)])
    return persons, who, own
