"""What mocapd published during a recorded take: the PoseFrames on /pose (the live solve, as the
recorder received it) and the skeleton they were solved with — the latest calibration's recorded
on /calibration/* (the live calibrator's), else the attached session's. `mocap export` writes a
recorded take from them without solving it again.

A take of several people (a session with "people" above 1) has one PoseFrame per person and
frame, each with its subject id: `subjects()` lists them and `of(id)` is one person's take, with
the skeleton of the suit they wore last (the suit whose sensors their PoseFrames list), else the
session's, and its times from the take's first pose (everyone's files on one clock)."""

from __future__ import annotations

import dataclasses
import tempfile
from pathlib import Path

import numpy as np

from mocap import _core
from mocap.errors import InputError
from mocap.io.session import Session
from mocap.net import wire
from mocap.recording import reader

POSE_TOPIC = "/pose"


@dataclasses.dataclass
class Published:
    poses: list  # wire.PoseFrame, in capture order, each frame once per subject
    skeleton: _core.Skeleton | None  # None: neither a calibration nor a session says it
    integrity: reader.Integrity
    suits: list = dataclasses.field(default_factory=list)  # several people: (sensor names, skeleton) per suit
    start_ns: int | None = None  # what times() counts from (None: the first pose's capture)

    def subjects(self) -> list[int]:
        """The subject ids of the poses, in order (one person: [0])."""
        return sorted({p.subject_id for p in self.poses})

    def of(self, subject: int) -> Published:
        """Subject `subject`'s poses, with the skeleton of the suit they wore last (else the take's)."""
        poses = [p for p in self.poses if p.subject_id == subject]
        if not poses:
            raise InputError(f"no subject {subject} in this take (subjects: {', '.join(map(str, self.subjects()))})")
        return Published(poses, worn_skeleton(poses, self.suits, self.skeleton), self.integrity,
                         start_ns=self.poses[0].capture_time_ns)  # everyone's times on the take's clock

    def positions(self) -> np.ndarray:
        """(F, J, 3) m: the joints as published, each frame with the calibration it was solved with."""
        return np.array([[[j.px, j.py, j.pz] for j in p.joints] for p in self.poses])

    def times(self) -> np.ndarray:
        """(F,) s from the first pose's capture (one person of several: the take's first)."""
        start = self.poses[0].capture_time_ns if self.start_ns is None else self.start_ns
        return np.array([p.capture_time_ns - start for p in self.poses]) * 1e-9

    def thetas(self) -> np.ndarray:
        return np.array([list(p.theta) for p in self.poses])

    def rate_hz(self) -> float:
        """The take's frame rate, from the median interval between captures (60 for one frame)."""
        if len(self.poses) < 2:
            return 60.0
        return float(1e9 / np.median(np.diff([p.capture_time_ns for p in self.poses])))


def suit_skeletons(session: Session, default: _core.Skeleton | None) -> list:
    """A session's suits as (their sensors' names, the skeleton they were calibrated on: the
    suit's, else `default`); none for a session of one person."""
    suits = []
    for suit in session.suits:
        skeleton = _core.Skeleton.load(str(session.base / suit["skeleton"])) if "skeleton" in suit else default
        suits.append(({site.name for site in _core.load_imu_sites(str(session.base / suit["imus"]), skeleton)}, skeleton))
    return suits


def worn_skeleton(poses: list, suits: list, default: _core.Skeleton | None) -> _core.Skeleton | None:
    """One person's skeleton: that of the suit (suit_skeletons) whose sensors their last
    PoseFrame with sensors lists, else `default`."""
    worn = next((set(p.imus) for p in reversed(poses) if p.imus), set())
    return next((skeleton for names, skeleton in suits if worn and worn <= names), default)


def subject_file(path: Path, subject: int) -> Path:
    """Where one person of several is written: the file's name with _subjectN before its suffix."""
    return path.with_name(f"{path.stem}_subject{subject}{path.suffix}")


def _decoded(message: reader.RecordedMessage):
    try:
        return wire.decode([message.type_name.encode(), message.payload])
    except wire.WireError:
        return None  # counted by the recorder when it was written; a damaged one is skipped here


def read(path: str | Path) -> Published:
    """The published poses of recording `path`; InputError when it has none."""
    poses: dict[tuple[int, int], wire.PoseFrame] = {}  # by (capture time, subject)
    latest_skeleton: tuple[int, str] | None = None
    with reader.Recording(path) as recording:
        for message in recording.messages():
            if message.topic == POSE_TOPIC and isinstance(pose := _decoded(message), wire.PoseFrame):
                poses.setdefault((pose.capture_time_ns, pose.subject_id), pose)
            elif message.topic.startswith("/calibration/") and isinstance(c := _decoded(message), wire.Calibration):
                if c.skeleton_json and (latest_skeleton is None or c.valid_from_ns >= latest_skeleton[0]):
                    latest_skeleton = (c.valid_from_ns, c.skeleton_json)
        if not poses:
            raise InputError(f"{path}: no solved poses ({POSE_TOPIC}) in this recording: record mocapd's output "
                             "with the inputs, or solve the inputs first (`mocap solve --recording`)")
        skeleton, suits = _skeletons(recording, latest_skeleton)
    ordered = [poses[key] for key in sorted(poses)]
    return Published(ordered, skeleton, recording.integrity, suits)


def _skeletons(recording: reader.Recording, calibrated: tuple[int, str] | None) -> tuple:
    """The take's skeleton (the latest calibration's, else the attached session's; None for
    neither) and the attached session's suits: (their sensors' names, their skeleton) each."""
    try:
        with tempfile.TemporaryDirectory() as folder:
            try:
                found = recording.session(folder)
            except InputError:
                if calibrated is None:
                    raise
                found = None  # the calibration recorded says the skeleton; no suits then
            session = None if found is None else Session.load(found)
            skeleton = _core.Skeleton.from_json(calibrated[1]) if calibrated is not None else (
                None if session is None else _core.Skeleton.load(str(session.file("skeleton"))))
            return skeleton, [] if session is None else suit_skeletons(session, skeleton)
    except ValueError as e:
        raise InputError(f"{recording.path}: its skeleton cannot be read ({e})") from None
