"""The calibration of a session's subject from the streams' messages — a recording's, or the
live calibrator's last seconds — and the calibrated session written as files.

The messages become frames as mocapd makes them (mocap.model.frames: the host's own input
path, fed by the messages' arrival times): the same subject choice, the same grouping of
camera frames, the IMUs interpolated to the frame times by the same rules (no reading across
a gap mocapd would not bridge), the frames the detector skipped (HS mode) kept as such. The
given session supplies the rig, the layout, the prior, the endpoints and the IMU set's
names and bones; its skeleton and mountings are replaced. A sensor of the set that sent
nothing usable is left out of the new IMU set (calibration.json lists it): mocapd then
counts its samples as from an unknown source rather than trusting a mounting nobody
measured.
"""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
from collections import defaultdict
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from mocap import _core
from mocap.calibration import informative, window
from mocap.calibration.calibration_input import CalibrationInput
from mocap.errors import InputError
from mocap.io.session import Session
from mocap.model import frames
from mocap.model.solver import imu_set_json, layout_json
from mocap.net import wire

INVALID_ORIENTATION = wire.ImuSample.STATUS_ORIENTATION_INVALID


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


@dataclasses.dataclass
class Synchronised:
    """A session's messages as the calibration reads them."""
    data: CalibrationInput  # the frames mocapd would solve
    dropped: dict[str, int]  # what the input path dropped, by reason
    rig: _core.Rig
    imu_set: list[str]  # the session's IMU names


def synchronised(messages: list[tuple[int, str, bytes]], session: Path, where: str) -> Synchronised:
    """The frames mocapd would solve of (arrival ns, type name, payload) messages in arrival
    order; InputError when no camera of the session detected anything (`where` names them)."""
    config = Session.load(session)
    skeleton = _core.Skeleton.load(str(config.file("skeleton")))
    rig = _core.Rig.load(str(config.file("rig")))
    imu_set = _core.load_imu_sites(str(config.file("imus")), skeleton)
    layout = _core.KeypointLayout.load(str(config.file("layout")), skeleton)
    path = frames.input_path(session)
    data = CalibrationInput.from_frames(frames.synchronise(path, messages), len(rig.cameras), layout.name,
                                        len(layout.names), [(s.name, s.bone) for s in imu_set])
    if data is None or not data.detected.any():
        raise InputError(f"{where}: no camera frame with detections of the session's cameras")
    return Synchronised(data, dict(path.dropped), rig, [s.name for s in imu_set])


def estimate(messages: Iterable[tuple[int, str, bytes]], session: Path, seconds: float, where: str,
             quick: bool = False, video_if_still: bool = False) -> Estimated:
    """_estimate; a numerical failure of it ("SVD did not converge": values that overflow) is
    an InputError naming `where`, not a message naming nothing."""
    try:
        return _estimate(messages, session, seconds, where, quick, video_if_still)
    except np.linalg.LinAlgError as e:
        raise InputError(f"{where}: the calibration from it failed numerically ({e}); look for extreme values "
                         "in its calibration (Calib.toml, rig), keypoints and IMU samples") from None


def _estimate(messages: Iterable[tuple[int, str, bytes]], session: Path, seconds: float, where: str,
              quick: bool = False, video_if_still: bool = False) -> Estimated:
    """The calibration of `session`'s subject from (arrival ns, type name, payload) messages
    of its cameras and IMU hubs in arrival order (a recording, the live calibrator's last
    seconds, a take folder's), synchronised as mocapd synchronises them; InputError when they
    cannot give one (`where` names them). IMUs too still to calibrate: an InputError, or with
    video_if_still a calibration without them (the report says why). quick: window.estimate's."""
    messages = list(messages)
    synced = synchronised(messages, session, where)
    data = synced.data
    first, score, why_not = informative.calibration_window(data, seconds)
    if why_not and not video_if_still:
        raise InputError(f"{where}: {why_not.split(';')[0]}: the performer should move (walk, "
                         f"swing the arms, bend) while the studio calibrates")
    used = data.without_imus() if why_not else data
    cal = window.estimate(synced.rig, used, seconds=seconds, first_frame=first, quick=quick)
    names = [s.name for s in cal.imus]
    window_frames = int(np.searchsorted(data.times, data.times[first] + seconds) - first)
    return Estimated(cal.skeleton.to_json(), json.dumps(imu_set_json(cal.skeleton, cal.imus), indent=1),
                     json.dumps(layout_json(cal.skeleton, cal.layout), indent=1),
                     {"frames": data.frames, "first_frame_time_ns": data.first_time_ns,
                      "span_ns": [messages[0][0], messages[-1][0]], "dropped": synced.dropped,
                      "window_motion_score_deg": score, "imus_calibrated": names,
                      "imus_missing": [s for s in synced.imu_set if data.readings is None
                                       or s not in data.readings.names],
                      "imus_not_used_because": why_not,
                      "skeleton": {"from_frames": window_frames, "scales": cal.skeleton_start.scales,
                                   "lengths_m": cal.skeleton_start.lengths_m,
                                   "frames_per_length": cal.skeleton_start.frames},
                      "window": cal.report})


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
    if config.curve is not None:  # the same host key file, named from the new session's folder
        key = os.path.relpath((config.base / config.curve.host_key).resolve(), out.resolve())
        calibrated.curve = dataclasses.replace(config.curve, host_key=key)
    calibrated = calibrated.with_solver(heading_time_constant=window.HEADING_TIME_CONSTANT_S, heading_baseline_s=0.0)
    floor = estimated.report.get("window", {}).get("floor_height_m")  # E_G's floor, when the window saw one
    if floor is not None:
        calibrated = calibrated.with_solver(floor_height=floor)
    calibrated.save(out / "session.json")
