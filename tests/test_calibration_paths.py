"""Calibrating from a recording and from the live streams of the same take gives the same
calibration: both turn the messages into frames by mocapd's own input path, at the
messages' arrival times, so the live calibrator's snapshot and the recording's messages in
that snapshot's span give the same frames, and the same window solve.

The messages are the ones the edge boxes send (mocap_edge.offline: the camera box's and the
IMU hub's own pieces), arriving when the simulated detector finishes or the hub sends; some
camera frames arrive later than the synchroniser waits, so its drops are part of what must
agree. No sockets: deterministic.
"""

import concurrent.futures
import json

import numpy as np
import pytest

from mocap import _core
from mocap.calibration import from_recording
from mocap.calibration import live as calibrator
from mocap.demo import studio as live_studio
from mocap.net import wire
from mocap.recording import recorder
from mocap_edge import offline

START_NS = 1_000_000_000_000  # the take's start on the studio's clock (long past: nothing waits)
LATE_NS = 40_000_000  # every 50th frame of the first camera arrives this much later (max_wait: 25 ms)


@pytest.fixture(scope="module")
def take(tmp_path_factory):
    """A 9 s simulated take's messages in arrival order, every 50th frame of the first camera
    late, and its session (the oracle's: the calibration replaces its skeleton and mountings)."""
    studio = live_studio.prepare(tmp_path_factory.mktemp("studio"), seconds=9.0, seed=7, calibration="oracle")
    messages = offline.studio_messages(studio.streams, START_NS)
    late = [(t + LATE_NS if isinstance(m, wire.KeypointFrame) and m.camera_id == studio.camera_ids[0]
             and m.frame_index % 50 == 7 else t, m) for t, m in messages]
    return studio, sorted(late, key=lambda m: m[0])


class Inline(concurrent.futures.Executor):
    """The calibrator's worker, run at once in this process."""

    def submit(self, fn, *args):
        f = concurrent.futures.Future()
        f.set_result(fn(*args))
        return f


class FakePub:
    def __init__(self):
        self.sent = []

    def send_multipart(self, frames):
        self.sent.append(frames)


def live_calibration(studio, messages, out):
    """The live calibrator hearing the messages at their arrival times: its first full
    calibration (report and files)."""
    now = [0]
    c = calibrator.LiveCalibrator(studio.session, out, 5.0, calibrator.Policy(), "calibrator",
                                  clock=lambda: now[0] * 1e-9, clock_ns=lambda: now[0])
    pub = FakePub()
    for arrival, msg in messages:
        now[0] = arrival
        c.hear(wire.encode(msg))
        c.step(Inline(), pub)
        if any(not p["window"]["quick"] for p in c.published):
            break
    full = [p for p in c.published if not p["window"]["quick"]]
    assert full, f"the live calibrator published {len(c.published)} calibrations, none in full"
    return full[0]


def test_a_recording_and_the_live_streams_of_a_take_give_the_same_calibration(take, tmp_path):
    studio, messages = take
    live = live_calibration(studio, messages, tmp_path / "live")
    path = tmp_path / "take.mcap"
    with recorder.Recorder(path) as r:
        r.attach_session(studio.session)
        for arrival, msg in messages:
            r.write(wire.encode(msg), arrival)
    report = from_recording.calibrate(path, tmp_path / "rec", span_ns=tuple(live["span_ns"]))

    assert report["frames"] == live["frames"] and report["imus_calibrated"] == live["imus_calibrated"]
    assert report["window"]["window_start_s"] == live["window"]["window_start_s"]
    assert report["dropped"] == live["dropped"] and sum(report["dropped"].values()) > 0, report["dropped"]
    a = _core.Skeleton.load(str(tmp_path / "live" / "skeleton.json"))
    b = _core.Skeleton.load(str(tmp_path / "rec" / "skeleton.json"))
    np.testing.assert_allclose(a.offsets, b.offsets, atol=1e-9)
    for name in ("imus.json", "layout.json"):
        np.testing.assert_allclose(_numbers(tmp_path / "live" / name), _numbers(tmp_path / "rec" / name), atol=1e-9)


def _numbers(path) -> np.ndarray:
    """Every number of a JSON file, in order."""
    out = []

    def walk(v):
        if isinstance(v, dict):
            for k in sorted(v):
                walk(v[k])
        elif isinstance(v, list):
            for x in v:
                walk(x)
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            out.append(float(v))

    walk(json.loads(path.read_text()))
    return np.array(out)
