"""Per-camera tracking of people's regions and the packing of every camera's regions into
one landmark inference (the paper's throughput trick, for a top-down model): the full-image
person detector runs only for a camera that has lost its people, or every
`redetect_every` frames to find newcomers.

Left/right consistency: when it cannot tell a person's front from the back, the landmark
model mirrors its reading (on the real Balancing trial, camera 2, frames 42-74: face, arms
and legs at once, in 20 of those 33 frames, often every other frame). Per track and
group (face, arms, legs) two readings are kept alive, the model's and its mirror image, each
with the cost of its best history: the keypoints' frame-to-frame travel in region sizes
(a two-state Viterbi filter). A frame is mirrored when the mirrored history is the cheaper.
The output is never the reference of the next frame, so one wrong decision does not make
every later correct reading look swapped (the earlier rule, "mirror when the mirror image
lies much nearer the previous output", latched so for the rest of a take). A frame whose two
readings lie less than twice as far apart as the nearer lies from the reference (sides
merged, or moved as far as they are apart) says nothing about the sides: it is passed as
given and bridged. The model's reading wins ties and costs nothing; the mirrored one costs
MIRROR_COST per keypoint and frame, so with no new evidence a correction expires, within
HOLD_FRAMES at most (docs/results_real.md has the figures)."""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap_edge.detect.base import Detector, Person
from mocap_edge.detect.layouts import Layout

MIRROR_COST = 1e-3  # region sizes per keypoint and frame: the prior against the mirrored reading
HOLD_FRAMES = 60  # a correction no frame supports lasts at most this long (1 s at 60 fps)
# A detected region whose centre lies this near a tracked one's (in region sizes) is that
# person. Nearer than people stand: one behind another is a region of its own, read by the
# landmark model and dropped after it only if it read the same person (SAME_PERSON).
NEW_REGION_APART = 0.1
SAME_PERSON = 0.15  # median distance between two people's confident keypoints, in region sizes
SURE_KEYPOINT = 0.5  # confidence


@dataclasses.dataclass(frozen=True)
class Sides:
    """A track's left/right state. reference: per group, the model's keypoints (as given) of
    the last frame that could tell its sides apart; belief: per group, the cost of the best
    history with the model's reading mirrored minus that with it as given (region sizes;
    negative: mirrored)."""

    reference: np.ndarray
    belief: np.ndarray


@dataclasses.dataclass
class Counts:
    frames: int = 0
    detector_runs: int = 0
    landmark_crops: int = 0
    landmark_batches: int = 0


class Tracker:
    def __init__(self, model: Detector, max_people: int = 2, min_presence: float | None = None,
                 redetect_every: int = 0, pack: bool = True) -> None:
        """min_presence: a person below it is dropped (default: the model's own).
        redetect_every 0: the person detector only when tracking is lost. pack False: one
        inference per crop and the detector on every frame (the benchmark's naive baseline)."""
        self.model, self.max_people = model, max_people
        self.min_presence = model.min_presence if min_presence is None else min_presence
        self.redetect_every, self.pack = redetect_every, pack
        self.tracks: dict[str, list] = {}
        self.counts = Counts()

    def step(self, images: dict[str, np.ndarray]) -> dict[str, list[Person]]:
        """People in one frame of each camera (frames taken at one trigger)."""
        crops, owners, previous = [], [], []
        for camera, image in images.items():
            tracks = self.tracks.get(camera, [])
            due = self.redetect_every and self.counts.frames % self.redetect_every == 0
            if not tracks or due or not self.pack:
                found = [(r, None) for r in self.model.detect(image)]
                self.counts.detector_runs += 1
                tracks = _merge(tracks if self.pack else [], found)[: self.max_people]
            crops += [(image, r) for r, _ in tracks]
            previous += [k for _, k in tracks]
            owners += [camera] * len(tracks)
        self.counts.frames += 1
        self.counts.landmark_crops += len(crops)
        if self.pack:
            people = self.model.landmarks(crops)
            self.counts.landmark_batches += 1 if crops else 0
        else:
            people = [p for c in crops for p in self.model.landmarks([c])]
            self.counts.landmark_batches += len(crops)
        out: dict[str, list[Person]] = {c: [] for c in images}
        self.tracks = {c: [] for c in images}
        sides: dict[int, Sides] = {}  # id(person) -> its track's left/right state
        for camera, person, before in zip(owners, people, previous):
            if person.presence >= self.min_presence:
                person, sides[id(person)] = _consistent(person, before, self.model.layout)
                out[camera].append(person)
        for camera in out:
            out[camera] = _distinct(out[camera])
            self.tracks[camera] = [(p.next_roi, sides[id(p)]) for p in out[camera]]
        return out


def _consistent(person: Person, before: Sides | None, layout: Layout) -> tuple[Person, Sides]:
    """The person with each left/right group mirrored where its mirrored history is the
    cheaper (module docstring), and the track's new state. A new track takes the model's word."""
    raw = person.keypoints
    if before is None:
        return person, Sides(raw.copy(), np.zeros(len(layout.groups)))
    k, reference, belief = raw.copy(), before.reference.copy(), before.belief.copy()
    for i, g in enumerate(layout.groups):
        update = _belief(raw, before.reference, before.belief[i], g, layout.mirror, person.next_roi.size)
        if update is None:
            continue  # no evidence about this group's sides: as given, reference kept
        belief[i], reference[g] = update, raw[g]
        if update < 0:
            k[g] = raw[layout.mirror][g]
    return dataclasses.replace(person, keypoints=k), Sides(reference, belief)


def _belief(raw: np.ndarray, reference: np.ndarray, belief: float, group: np.ndarray, mirror: np.ndarray,
            size: float) -> float | None:
    """One step of the group's two-state filter, or None when the frame cannot tell the
    sides apart: its reading and mirror image lie less than twice as far apart as the nearer
    of them lies from the reference (sides merged, or a move as large as their distance:
    it could continue either; random keypoints never tell)."""
    if not size > 0:
        return None

    def travel(a: np.ndarray, b: np.ndarray) -> float:
        return float(np.linalg.norm(a[group, :2] - b[group, :2], axis=1).sum()) / size

    stay, cross, apart = travel(raw, reference), travel(raw, reference[mirror]), travel(raw, raw[mirror])
    if apart <= 2 * min(stay, cross):
        return None
    as_given = min(stay, belief + cross)
    mirrored = min(cross, belief + stay) + MIRROR_COST * len(group)
    bound = HOLD_FRAMES * MIRROR_COST * len(group)
    return float(np.clip(mirrored - as_given, -bound, bound))


def _merge(tracked: list, found: list) -> list:
    """Tracked (region, left/right state) first, then detected ones that are not one of them."""
    out = list(tracked)
    for r, k in found:
        if all(np.hypot(*(r.centre - t.centre)) > NEW_REGION_APART * max(r.size, t.size) for t, _ in out):
            out.append((r, k))
    return out


def _same_person(a: Person, b: Person) -> bool:
    """Whether two readings are of one person: their keypoints (the confident in both, else
    all) lie within SAME_PERSON region sizes of each other (median)."""
    both = (a.keypoints[:, 2] > SURE_KEYPOINT) & (b.keypoints[:, 2] > SURE_KEYPOINT)
    if both.sum() < 5:
        both[:] = True
    apart = np.median(np.linalg.norm(a.keypoints[both, :2] - b.keypoints[both, :2], axis=1))
    return bool(apart <= SAME_PERSON * max(a.next_roi.size, b.next_roi.size))


def _distinct(people: list[Person]) -> list[Person]:
    """Drops a person whose crop converged onto another's (the one with less presence): two
    regions near each other may hold two people, one behind the other."""
    people = sorted(people, key=lambda p: -p.presence)
    kept: list[Person] = []
    for p in people:
        if not any(_same_person(p, k) for k in kept):
            kept.append(p)
    return kept
