"""The calibration of a session's subject from the streams' messages — a recording's, or the
live calibrator's last seconds — and the calibrated session written as files.

Camera frames are grouped by capture time (each camera's frame nearest a reference camera's
within half a frame period); the subject is chosen per camera as for take folders
(mocap.model.subject); IMU samples are taken per sensor (invalid readings dropped). The
given session supplies the rig, the layout, the prior, the endpoints and the IMU set's
names and bones; its skeleton and mountings are replaced. A sensor of the set that sent
nothing usable is left out of the new IMU set (calibration.json lists it): mocapd then
counts its samples as from an unknown source rather than trusting a mounting nobody
measured.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from collections import defaultdict
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from mocap import _core
from mocap.calibration import informative, window
from mocap.calibration.calibration_input import CalibrationInput
from mocap.calibration.readings import readings_at
from mocap.errors import InputError
from mocap.io.session import Session
from mocap.model.solver import imu_set_json, layout_json
from mocap.model.subject import LAYOUT_SIZES, choose_subject
from mocap.net import wire

INVALID_ORIENTATION, INVALID_ACCELERATION = 1, 2  # ImuSample.Status bits


def _inputs(messages: Iterable[tuple[str, bytes]], camera_names: list[str], where: str):
    """Per camera [(capture_time_ns, [(K, 3) per person])], per sensor [(time_ns, q wxyz, a)],
    the keypoint layout, from (type name, payload) messages."""
    cams, imus, layouts = defaultdict(list), defaultdict(list), set()
    for type_name, payload in messages:
        if type_name == "mocap.v1.KeypointFrame":
            f = wire.KeypointFrame.FromString(payload)
            if f.camera_id not in camera_names or not f.detected:
                continue
            layouts.add(f.keypoint_layout)
            people = [np.stack([p.x, p.y, p.confidence], axis=1) for p in f.persons
                      if len(p.x) == len(p.y) == len(p.confidence)]
            cams[f.camera_id].append((f.capture_time_ns, people))
        elif type_name == "mocap.v1.ImuBatch":
            for s in wire.ImuBatch.FromString(payload).samples:
                q = [np.nan] * 4 if s.status & INVALID_ORIENTATION else [s.qw, s.qx, s.qy, s.qz]
                a = [np.nan] * 3 if s.status & INVALID_ACCELERATION else [s.ax, s.ay, s.az]
                imus[s.sensor_id].append((s.sample_time_ns, q, a))
    if len(layouts) > 1:
        raise InputError(f"{where}: the cameras use different keypoint layouts {sorted(layouts)}")
    return cams, imus, layouts.pop() if layouts else None


def _frames(cams: dict, camera_names: list[str], k: int) -> tuple[np.ndarray, np.ndarray]:
    """(F,) capture times (ns) of the reference camera (the one with most frames) and the
    subject's keypoints (F, C, K, 3)."""
    reference = max(cams, key=lambda c: len(cams[c]))
    times = np.array(sorted(t for t, _ in cams[reference]))
    half = 0.5 * float(np.median(np.diff(times))) if len(times) > 1 else 1e9
    people = [[np.zeros((0, k, 3)) for _ in times] for _ in camera_names]
    for c, name in enumerate(camera_names):
        for t, persons in cams.get(name, []):
            f = int(np.argmin(np.abs(times - t)))
            fitting = [p for p in persons if p.shape == (k, 3) and np.isfinite(p).all()]
            if abs(times[f] - t) <= half and fitting:
                people[c][f] = np.array(fitting)
    return times, choose_subject(people, len(times), k)


def _sensor(rows: list, t0: int) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """One sensor's (times s from t0, quaternions, accelerations), sorted, one sample per
    time, valid readings only; None with fewer than two."""
    if len(rows) < 2:
        return None
    t = np.array([r[0] for r in rows], dtype=np.int64)
    order = np.argsort(t, kind="stable")
    t, unique = np.unique(t[order], return_index=True)
    q = np.array([rows[i][1] for i in order[unique]])
    a = np.array([rows[i][2] for i in order[unique]])
    ok = np.isfinite(q).all(axis=1) & np.isfinite(a).all(axis=1)
    return ((t[ok] - t0) * 1e-9, q[ok], a[ok]) if ok.sum() >= 2 else None


class MotionWatch:
    """The IMUs' motion score (informative.window_score) over the last `seconds` of live samples."""

    def __init__(self, seconds: float):
        self.seconds = seconds
        self.samples: dict[str, list[tuple[int, list[float]]]] = defaultdict(list)  # sensor -> (ns, wxyz)

    def add(self, batch) -> None:
        for s in batch.samples:
            if not s.status & INVALID_ORIENTATION:
                self.samples[s.sensor_id].append((s.sample_time_ns, [s.qw, s.qx, s.qy, s.qz]))

    def score(self) -> float:
        """NaN when no IMU sent anything in the last `seconds` (of the newest sample's clock: a
        sensor that stopped sending drops out)."""
        if not self.samples:
            return float("nan")
        since = max(rows[-1][0] for rows in self.samples.values()) - self.seconds * 1e9
        spreads = []
        for name in list(self.samples):
            rows = self.samples[name] = [r for r in self.samples[name] if r[0] >= since]
            if not rows:
                del self.samples[name]
                continue
            q = np.array([r[1] for r in rows], dtype=float)
            q /= np.maximum(np.linalg.norm(q, axis=1, keepdims=True), 1e-12)
            spreads.append(informative.tilt_spread_deg(q[:, None])[0])
        return float(np.nanmedian(spreads)) if np.isfinite(spreads).any() else float("nan")


@dataclasses.dataclass
class Estimated:
    """A session's calibration estimated from messages, in the host's file formats (as a
    Calibration message carries it), and what was done."""
    skeleton_json: str  # mocap.skeleton/1
    imus_json: str  # mocap.imus/1
    layout_json: str  # mocap.layout/1
    report: dict


def estimate(messages: Iterable[tuple[str, bytes]], session: Path, seconds: float, where: str,
             quick: bool = False) -> Estimated:
    """The calibration of `session`'s subject from (type name, payload) messages of its
    cameras and IMU hubs (a recording, or the live calibrator's last seconds); InputError
    when they cannot give one (`where` names them). quick: window.estimate's."""
    config = Session.load(session)
    skeleton = _core.Skeleton.load(str(config.file("skeleton")))
    rig = _core.Rig.load(str(config.file("rig")))
    imu_set = _core.load_imu_sites(str(config.file("imus")), skeleton)
    names = [c.name for c in rig.cameras]
    cams, samples, layout = _inputs(messages, names, where)
    if not cams or layout is None:
        raise InputError(f"{where}: no camera frame with detections of the session's cameras")
    times_ns, det = _frames(cams, names, LAYOUT_SIZES[layout])
    t0 = times_ns[0]
    sensors = [(s.name, s.bone, *found) for s in imu_set if (found := _sensor(samples.get(s.name, []), t0))]
    frame_times = (times_ns - t0) * 1e-9
    readings = readings_at(frame_times, sensors) if sensors else None
    data = CalibrationInput.from_arrays(det, frame_times, layout, readings)
    first, score, why_not = informative.calibration_window(data, seconds)
    if why_not:
        raise InputError(f"{where}: {why_not.split(';')[0]}: the performer should move (walk, "
                         f"swing the arms, bend) while the studio calibrates")
    cal = window.estimate(rig, data, seconds=seconds, first_frame=first, quick=quick)
    used = [s[0] for s in sensors]
    return Estimated(cal.skeleton.to_json(), json.dumps(imu_set_json(cal.skeleton, cal.imus), indent=1),
                     json.dumps(layout_json(cal.skeleton, cal.layout), indent=1),
                     {"frames": len(frame_times), "first_frame_time_ns": int(t0),
                      "window_motion_score_deg": score, "imus_calibrated": used,
                      "imus_missing": [s.name for s in imu_set if s.name not in used], "window": cal.report})


def write_session(out: Path, session: Path, estimated: Estimated, report: dict) -> None:
    """Writes `session` with the estimated calibration into `out` (session.json, skeleton.json,
    imus.json, layout.json, calibration.json = report, copies of the rig and the prior)."""
    config = Session.load(session)
    out.mkdir(parents=True, exist_ok=True)
    (out / "skeleton.json").write_text(estimated.skeleton_json)
    (out / "imus.json").write_text(estimated.imus_json)
    (out / "layout.json").write_text(estimated.layout_json)
    (out / "calibration.json").write_text(json.dumps(report, indent=1))
    copied = {}
    for key in ("rig", "prior"):  # copied: an attached session lives in a temporary folder
        source = config.file(key)
        if source is not None and source.resolve() != (out / source.name).resolve():
            shutil.copyfile(source, out / source.name)
        copied[key] = None if source is None else source.name
    # Headings fitted to this video: tracked against it, without a baseline (solver.h).
    calibrated = dataclasses.replace(config, skeleton="skeleton.json", imus="imus.json", layout="layout.json",
                                     imus_calibrated=True, base=out, **copied)
    calibrated = calibrated.with_solver(heading_time_constant=window.HEADING_TIME_CONSTANT_S, heading_baseline_s=0.0)
    calibrated.save(out / "session.json")
