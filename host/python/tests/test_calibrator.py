"""The live calibrator's policy and buffer (mocap.calibration.live): when it calibrates and what it
keeps. Its run beside mocapd is tested end to end in tests/test_live.py."""

import contextlib
import json
import os
import select
import signal
import subprocess
import sys

import numpy as np
import pytest

from mocap.calibration import informative
from mocap.calibration import live as calibrator
from mocap.calibration.from_messages import Estimated
from mocap.io.session import Session

GOOD, MIN = informative.GOOD_SCORE_DEG, informative.MIN_SCORE_DEG


def test_the_first_calibration_waits_for_motion_then_settles_for_less():
    p = calibrator.Policy(max_wait_s=30.0)
    assert not p.due(0.6, 10.0, None, np.inf)  # standing still
    assert p.due(GOOD + 1, 6.0, None, np.inf)  # moving: at once
    assert not p.due(GOOD - 5, 10.0, None, np.inf)  # moving a little: wait for more ...
    assert p.due(GOOD - 5, 31.0, None, np.inf)  # ... but not for ever
    assert not p.due(MIN - 1, 60.0, None, np.inf)  # too still to calibrate from, however long


def test_a_calibration_is_refined_when_the_motion_is_much_richer_and_not_too_often():
    p = calibrator.Policy(refine_factor=1.5, min_interval_s=20.0)
    assert not p.due(20.0, 60.0, 18.0, 30.0)  # about as rich as the window in use
    assert p.due(28.0, 60.0, 18.0, 30.0)
    assert not p.due(28.0, 60.0, 18.0, 10.0)  # the last calibration started 10 s ago


def test_without_imus_the_skeleton_comes_from_video_and_imus_that_join_later_are_calibrated():
    p = calibrator.Policy(min_interval_s=20.0)
    assert p.due(float("nan"), 5.0, None, np.inf)  # no IMU sends: video alone, at once
    assert not p.due(float("nan"), 60.0, float("nan"), 30.0)  # and nothing more while none sends
    assert not p.due(GOOD + 1, 60.0, float("nan"), 10.0)  # the hub came: not before the interval ...
    assert p.due(GOOD + 1, 60.0, float("nan"), 30.0)  # ... then with the IMUs
    assert not p.due(MIN + 1, 60.0, float("nan"), 30.0)  # once they move enough


def test_the_buffer_keeps_the_last_seconds_by_arrival():
    b = calibrator.Buffer(keep_s=2.0)
    for k in range(50):
        b.add(int(k * 0.1e9), "mocap.v1.ImuBatch", bytes([k]))
    kept = b.snapshot()
    assert len(kept) == 21 and kept[0] == (int(29 * 0.1e9), "mocap.v1.ImuBatch", bytes([29]))
    assert kept[-1][2] == bytes([49])  # with their arrival times: the synchroniser's clock


class FakePub:
    def __init__(self):
        self.sent = []

    def send_multipart(self, frames):
        self.sent.append(frames)


class Immediate:
    """An executor that runs the job at once (or fails it)."""

    def __init__(self, fail: bool = False):
        self.fail, self.calls, self.quick = fail, 0, []

    def submit(self, fn, *args):
        import concurrent.futures

        self.calls += 1
        self.quick.append(args[-1])
        f = concurrent.futures.Future()
        if self.fail:
            f.set_exception(ValueError("calibration: the window solve failed"))
        else:
            f.set_result(Estimated('{"skeleton": 1}', '{"imus": []}', '{"layout": 1}',
                                   {"frames": 3, "window": {"quick": args[-1]}}))
        return f


def moving_batches(seconds: float, amplitude_deg: float):
    """ImuBatch payloads of two sensors tilting sinusoidally, 100 Hz, 10 samples each."""
    from mocap.net import wire
    from test_informative import readings

    t = np.arange(int(seconds * 100)) / 100.0
    q = readings(amplitude_deg * np.sin(2 * np.pi * t), sensors=2)
    for k in range(0, len(t), 10):
        b = wire.ImuBatch(hub_id="hub0", sequence=k // 10)
        for f in range(k, k + 10):
            for i in range(2):
                s = b.samples.add(sensor_id=f"s{i}", sample_time_ns=int(t[f] * 1e9))
                s.qw, s.qx, s.qy, s.qz = q[f, i]
        yield t[k], wire.encode(b)


def test_the_calibrator_publishes_when_due_repeats_and_survives_a_failed_estimate(tmp_path):
    from mocap.net import wire

    now = [0.0]
    session = tmp_path / "session.json"
    Session("s.json", "r.json", "l.json", "i.json", ["tcp://127.0.0.1:5600"], "tcp://*:5700").save(session)
    (tmp_path / "r.json").write_text("{}")  # copied into the calibrated session
    for fail in (True, False):
        c = calibrator.LiveCalibrator(session, tmp_path / f"out{fail}", 5.0, calibrator.Policy(), "calibrator",
                                      clock=lambda: now[0])
        pool, pub = Immediate(fail), FakePub()
        for t, frames in moving_batches(8.0, 30.0):
            now[0] = t
            c.hear(frames)
            c.step(pool, pub)
        assert pool.calls >= 1  # due once 5 s of motion were heard
        if fail:  # logged, nothing published, the calibrator goes on
            assert pub.sent == [] and c.published == []
            continue
        # The first quick, the same seconds in full at once after it.
        assert len(c.published) == 2 and pool.quick == [True, False]
        first = wire.decode(pub.sent[-1])
        assert isinstance(first, wire.Calibration) and first.sequence == 1 and first.skeleton_json == '{"skeleton": 1}'
        now[0] += calibrator.REPEAT_S + 0.1
        c.step(pool, pub)
        assert len(pub.sent) >= 2 and wire.decode(pub.sent[-1]) == first  # repeated for late joiners
        assert (tmp_path / "outFalse" / "calibration.json").is_file()
        history = [json.loads(line) for line in (tmp_path / "outFalse" / calibrator.HISTORY).read_text().splitlines()]
        assert [(h["sequence"], h["quick"]) for h in history] == [(0, True), (1, False)]


def test_a_worker_that_died_is_replaced():
    """Killed or out of memory: its job fails, the next runs in a new worker process."""
    import concurrent.futures

    with calibrator.WorkerPool() as pool:
        with pytest.raises(concurrent.futures.process.BrokenProcessPool):
            pool.submit(os._exit, 1).result(timeout=30)
        assert pool.submit(pow, 2, 10).result(timeout=30) == 1024


WORKER_TIMEOUT_S = 30.0  # bound on each wait for the worker; generous for loaded machines, never a measured time
PARENT_SCRIPT = """
import os, sys, time
from mocap.calibration import live as calibrator
fd = int(sys.argv[1])
def job():  # in the worker: says who it is, then works for a long time
    os.write(fd, b"%d" % os.getpid())
    time.sleep(600)
with calibrator.WorkerPool() as pool:
    pool.submit(job)
    time.sleep(600)
"""


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_the_worker_ends_with_its_calibrator(sig):
    """A calibrator killed (SIGKILL, a crashed box) or stopped (SIGTERM, `systemctl stop`)
    while its worker computes leaves no worker behind: the kernel kills the worker as its
    parent dies (PR_SET_PDEATHSIG). Without it the forked worker lived on, blocked forever."""
    read_end, write_end = os.pipe()
    parent = subprocess.Popen([sys.executable, "-c", PARENT_SCRIPT, str(write_end)], pass_fds=[write_end])
    os.close(write_end)
    worker_fd = None
    try:
        assert select.select([read_end], [], [], WORKER_TIMEOUT_S)[0], "the worker never started"
        worker = int(os.read(read_end, 32))
        worker_fd = os.pidfd_open(worker)  # readable once the worker has ended
        parent.send_signal(sig)
        assert parent.wait(timeout=WORKER_TIMEOUT_S) == -sig
        assert select.select([worker_fd], [], [], WORKER_TIMEOUT_S)[0], "the worker outlived its calibrator"
        with contextlib.suppress(ChildProcessError):  # re-parented to the suite's pytest (a subreaper): reaped
            os.waitpid(worker, os.WNOHANG)
    finally:
        parent.kill()
        parent.wait()
        os.close(read_end)
        if worker_fd is not None:
            os.close(worker_fd)
