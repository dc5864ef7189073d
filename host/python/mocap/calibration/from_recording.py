"""`mocap calibrate --recording FILE [--session S] --out DIR`: a live session whose skeleton
and IMU sites are estimated from a few seconds of a recording of the studio's streams
(`mocap record`), so that mocapd captures without oracle calibration: the first seconds in
which the IMUs move enough (mocap.calibration.informative; a performer standing still leaves
their headings undetermined). With `--connect EP... --session S` it records from the running
edge boxes and IMU hubs first (DIR/calibration.mcap, kept), until the last seconds had that
motion (at most max_seconds), then calibrates from them: `mocapd DIR/session.json` captures.

The recording's messages are calibrated from as mocap.calibration.from_messages says; the
given session (by default the one attached to the recording) supplies the rig, the layout,
the prior, the endpoints and the IMU set. DIR receives session.json, skeleton.json, imus.json,
layout.json (the keypoint sites, estimated) and calibration.json, and a copy of the
session's rig and prior files.
"""

from __future__ import annotations

import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from mocap.calibration import informative, window
from mocap.calibration.from_messages import MotionWatch, estimate, write_session
from mocap.errors import InputError
from mocap.net import wire
from mocap.recording import reader, recorder


def record_window(endpoints: list[str], path: Path, session: Path, seconds: float = window.SECONDS,
                  timeout_s: float = 60.0, max_seconds: float = 30.0) -> recorder.Counts:
    """Records the streams at `endpoints` until `seconds` (and a margin of 1.5 s) have passed
    since the first message and the IMUs moved enough in the last `seconds`
    (informative.GOOD_SCORE_DEG; no IMU: at once), or max_seconds have; InputError if nothing
    came within timeout_s."""
    stop = threading.Event()
    seen = {"first": None, "last": None, "checked": 0.0}  # monotonic times
    motion = MotionWatch(seconds)

    def on_record(_topic: str, message) -> None:
        seen["last"] = time.monotonic()
        seen["first"] = seen["first"] or seen["last"]
        if isinstance(message, wire.ImuBatch):
            motion.add(message)
        elapsed = seen["last"] - seen["first"]
        if elapsed > seconds + 1.5 and seen["last"] - seen["checked"] > 0.5:
            seen["checked"] = seen["last"]
            score = motion.score()
            if not np.isfinite(score) or score >= informative.GOOD_SCORE_DEG or elapsed > max_seconds + 1.5:
                stop.set()

    timer = threading.Timer(timeout_s, stop.set)
    timer.start()
    try:
        counts = recorder.record(endpoints, path, None, stop, on_record, session=session)
    finally:
        timer.cancel()
    if seen["first"] is None or seen["last"] - seen["first"] < seconds:
        raise InputError(f"{' '.join(endpoints)}: {'nothing' if seen['first'] is None else 'too little'} received in "
                         f"{timeout_s:.0f} s; are the edge boxes and hubs publishing there?")
    return counts


def calibrate(recording_path: Path, out: Path, session: Path | None = None, seconds: float = window.SECONDS,
              span_ns: tuple[int, int] | None = None) -> dict:
    """Calibrates `session` (default: the one attached to the recording) from the recording's
    camera and IMU messages, at their recorded arrival times (span_ns: only those that arrived
    in [first, last], e.g. a live calibration's span, to repeat it), and writes the calibrated
    session into `out`; the report."""
    recording_path, out = Path(recording_path), Path(out)
    first, last = span_ns if span_ns is not None else (-(2 ** 63), 2 ** 63 - 1)
    with tempfile.TemporaryDirectory() as attached, reader.Recording(recording_path) as recording:
        if session is None:
            session = recording.session(attached)
            if session is None:
                raise InputError(f"{recording_path}: no session is attached; give one with --session")
        session = Path(session).resolve()
        messages = ((m.log_time_ns, m.type_name, m.payload) for m in recording.messages()
                    if first <= m.log_time_ns <= last)
        try:
            estimated = estimate(messages, session, seconds, str(recording_path))
        except InputError as e:
            if recording.integrity.intact:
                raise
            raise InputError(f"{e} (the recording: {recording.integrity.describe()})") from None
        report = {"recording": str(recording_path), "session": str(session), **estimated.report,
                  "integrity": recording.integrity.as_dict()}
        write_session(out, session, estimated, report)
    return report
