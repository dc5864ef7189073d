"""The live calibrator, `mocap calibrate --connect EP... --session S --out DIR --follow
--publish EP`: beside mocapd, it listens to the edge boxes and IMU hubs, keeps their last
seconds, and publishes a Calibration (proto/mocap/v1/calibration.proto) that mocapd applies
from its capture time on (a session may start with "imus_calibrated": false: mocapd then
solves from video alone until the first one comes).

When (the Policy):
- the first calibration as soon as the last `seconds` had enough motion
  (informative.GOOD_SCORE_DEG), or, after max_wait_s, from the last `seconds` if they move at
  all (informative.MIN_SCORE_DEG);
- then again, refined as capture goes on, when the last `seconds` move REFINE_FACTOR times as
  much as the window in use did (a performer who only shuffled at first and walks now), at
  most every MIN_INTERVAL_S;
- with no IMU sending, the skeleton and keypoint sites from video alone after `seconds`
  (a video-only studio, or a hub that is late: when its IMUs move, a calibration with them
  follows).

Each calibration is computed in a worker process at low priority (about 12 s on two cores;
mocapd keeps its latency; a worker that died is replaced), written to DIR as a session (so a
restarted mocapd starts with the latest; DIR/calibrations.jsonl lists every one), and
published; the latest is published again every REPEAT_S for hosts that connect later
(mocapd takes a sequence once). The first is quick (window.estimate's quick:
one window solve, about half the time) and the same seconds in full follow it at once.
"""

from __future__ import annotations

import collections
import concurrent.futures
import dataclasses
import json
import logging
import os
import threading
import time
from collections.abc import Callable
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

import numpy as np
import zmq

from mocap import processes
from mocap.calibration import informative, window
from mocap.calibration.from_messages import Estimated, MotionWatch, estimate, write_session
from mocap.io.session import Session
from mocap.net import transport, wire
from mocap.net.keys import ServerKeys

log = logging.getLogger(__name__)

REFINE_FACTOR = 1.5
MIN_INTERVAL_S = 20.0
REPEAT_S = 2.0
CHECK_S = 1.0  # how often the policy looks at the motion
MARGIN_S = 1.5  # kept beyond the window: the cameras' and IMUs' latest messages differ
HISTORY = "calibrations.jsonl"  # in DIR: every calibration published, one JSON object per line


@dataclasses.dataclass
class Policy:
    """When to calibrate, from the motion score of the last `seconds` (see the module docstring)."""
    max_wait_s: float = 30.0
    refine_factor: float = REFINE_FACTOR
    min_interval_s: float = MIN_INTERVAL_S

    def due(self, score: float, elapsed_s: float, in_use: float | None, since_last_s: float) -> bool:
        """Calibrate now? score: the last seconds' motion (NaN: no IMU readings in them);
        elapsed_s: since the first message (at least the window's length); in_use: the score
        of the calibration in use (None: none yet; NaN: one from video alone); since_last_s:
        since the last calibration was started."""
        moving = bool(np.isfinite(score) and score >= informative.MIN_SCORE_DEG)
        if in_use is None:
            if not np.isfinite(score):  # no IMU sends: the skeleton from video alone
                return True
            return moving and (score >= informative.GOOD_SCORE_DEG or elapsed_s >= self.max_wait_s)
        if since_last_s < self.min_interval_s or not moving:
            return False
        if not np.isfinite(in_use):  # calibrated from video alone, and now IMUs move
            return score >= informative.GOOD_SCORE_DEG
        return score >= self.refine_factor * in_use


class Buffer:
    """The camera and IMU messages of the last `keep_s` seconds, by arrival."""

    def __init__(self, keep_s: float):
        self.keep_ns = int(keep_s * 1e9)
        self.items: collections.deque[tuple[int, str, bytes]] = collections.deque()

    def add(self, arrival_ns: int, type_name: str, payload: bytes) -> None:
        self.items.append((arrival_ns, type_name, payload))
        while self.items and self.items[0][0] < arrival_ns - self.keep_ns:
            self.items.popleft()

    def snapshot(self) -> list[tuple[int, str, bytes]]:
        """(arrival ns, type name, payload) of each message kept, in arrival order."""
        return list(self.items)


def _estimate(messages: list[tuple[int, str, bytes]], session: str, seconds: float, quick: bool) -> Estimated:
    """In the worker process."""
    return estimate(messages, Path(session), seconds, "the live streams", quick=quick)


def _worker_start(die_with_parent: Callable[[], None]) -> None:
    """In the worker: low priority, and ended with its parent (mocap.processes). A forked
    worker outlives a killed parent otherwise (blocked on a pipe it holds both ends of). The
    kernel's parent-death signal rather than spawn and a pipe only the parent holds: nothing
    has to run in the worker (no watcher thread to read that pipe and exit, whatever the job
    is doing), it holds for SIGKILL of the parent as for SIGTERM, and the pool keeps fork. It
    is sent when the *thread* that forked the worker ends: WorkerPool is made and used by one
    thread (follow's), which outlives the pool."""
    os.nice(10)
    die_with_parent()


def _start_worker() -> concurrent.futures.ProcessPoolExecutor:
    return concurrent.futures.ProcessPoolExecutor(1, initializer=_worker_start,
                                                 initargs=(processes.die_with_parent(),))


class WorkerPool:
    """The calibrator's worker: one low-priority process, replaced when it died (killed, out
    of memory): the job it ran fails (logged), the next one runs in a new process."""

    def __init__(self, start=_start_worker):
        self.start = start
        self.pool = start()

    def submit(self, fn, *args) -> concurrent.futures.Future:
        try:
            return self.pool.submit(fn, *args)
        except BrokenProcessPool:
            log.warning("the calibration worker process died; starting another")
            self.pool.shutdown(wait=False, cancel_futures=True)
            self.pool = self.start()
            return self.pool.submit(fn, *args)

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(self, *_) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


def message(source: str, sequence: int, estimated: Estimated, valid_from_ns: int) -> wire.Calibration:
    return wire.Calibration(source=source, sequence=sequence, valid_from_ns=valid_from_ns,
                            skeleton_json=estimated.skeleton_json, imus_json=estimated.imus_json,
                            layout_json=estimated.layout_json, report_json=json.dumps(estimated.report))


class LiveCalibrator:
    """The calibrator's state between messages: what it heard, the job under way, what it
    published (see the module docstring)."""

    def __init__(self, session: Path, out: Path, seconds: float, policy: Policy, source: str,
                 clock=time.monotonic, clock_ns=time.time_ns):
        """clock: s, for the policy's intervals; clock_ns: the arrival clock the messages are
        stamped with (the host's, as mocapd's)."""
        self.session, self.out, self.seconds, self.policy, self.source = session, out, seconds, policy, source
        self.clock, self.clock_ns = clock, clock_ns
        self.buffer, self.motion = Buffer(seconds + MARGIN_S), MotionWatch(seconds)
        self.published: list[dict] = []
        self.latest: wire.Calibration | None = None
        self.job: concurrent.futures.Future | None = None
        self.job_score, self.in_use = float("nan"), None
        self.full_of: list[tuple[int, str, bytes]] | None = None  # after a quick one: these, in full
        self.first = self.last_check = self.last_start = self.last_sent = None

    def hear(self, frames: list[bytes]) -> None:
        try:
            msg = wire.decode(frames)
        except wire.WireError:
            return  # mocapd counts what is malformed; the calibrator only skips it
        if isinstance(msg, (wire.KeypointFrame, wire.ImuBatch)):
            self.buffer.add(self.clock_ns(), msg.DESCRIPTOR.full_name, bytes(frames[1]))
            self.first = self.first or self.clock()
        if isinstance(msg, wire.ImuBatch):
            self.motion.add(msg)

    def step(self, pool: concurrent.futures.Executor, pub: zmq.Socket) -> None:
        """Publishes a finished calibration, repeats the latest, starts one when due."""
        now = self.clock()
        if self.job is not None and self.job.done():
            self._publish(self.job, pub, now)
            self.job = None
        if self.latest is not None and now - self.last_sent >= REPEAT_S:
            pub.send_multipart(wire.encode(self.latest))
            self.last_sent = now
        if self.job is None and self.full_of is not None:  # the quick one is out: now in full
            self.job, self.full_of = pool.submit(_estimate, self.full_of, str(self.session), self.seconds, False), None
        if self.job is None and self.first is not None and (self.last_check is None or now - self.last_check >= CHECK_S):
            self.last_check = now
            score, since = self.motion.score(), now - self.last_start if self.last_start else np.inf
            if now - self.first >= self.seconds and self.policy.due(score, now - self.first, self.in_use, since):
                messages, quick = self.buffer.snapshot(), self.in_use is None
                self.job = pool.submit(_estimate, messages, str(self.session), self.seconds, quick)
                self.job_score, self.last_start = score, now
                self.full_of = messages if quick else None

    def _publish(self, job: concurrent.futures.Future, pub: zmq.Socket, now: float) -> None:
        try:
            estimated = job.result()
        except Exception as e:  # noqa: BLE001 - a failed estimate is logged; the calibrator goes on
            log.warning("calibration failed: %s", e)
            self.full_of = None
            return
        valid_from = self.clock_ns()
        self.latest = message(self.source, len(self.published), estimated, valid_from)
        self.in_use = self.job_score
        record = {"sequence": self.latest.sequence, "valid_from_ns": valid_from,
                  "score_deg": self.job_score if np.isfinite(self.job_score) else None, **estimated.report}
        write_session(self.out, self.session, estimated, record)
        with open(self.out / HISTORY, "a") as f:  # one line per calibration published
            f.write(json.dumps({k: record[k] for k in ("sequence", "valid_from_ns", "score_deg")} |
                               {"quick": record["window"]["quick"], "frames": record["frames"]}) + "\n")
        pub.send_multipart(wire.encode(self.latest))
        self.last_sent = now
        self.published.append(record)
        log.info("calibration %d published (the last %.0f s: IMUs moved %.1f deg)", self.latest.sequence,
                 self.seconds, self.job_score)


def follow(endpoints: list[str], session: Path, out: Path, publish: str, seconds: float = window.SECONDS,
           policy: Policy = Policy(), stop: threading.Event | None = None, source: str = "calibrator",
           duration_s: float | None = None) -> list[dict]:
    """Runs the live calibrator until `stop` is set (or duration_s passed); returns what it
    published, one dict per calibration (sequence, valid_from_ns, window score, report)."""
    stop = stop or threading.Event()
    calibrator = LiveCalibrator(Path(session).resolve(), Path(out), seconds, policy, source)
    deadline = None if duration_s is None else time.monotonic() + duration_s
    context = zmq.Context.instance()
    # With the session's keys: a client of the boxes, and a server to mocapd, with the host's key pair.
    config = Session.load(session)
    client, pair = config.client_keys(), config.host_keys()
    server = None if pair is None else ServerKeys(pair)
    with WorkerPool() as pool, transport.subscriber(context, endpoints, keys=client) as sub, \
            transport.publisher(context, publish, keys=server) as pub:
        while not stop.is_set() and (deadline is None or time.monotonic() < deadline):
            if sub.poll(100):
                while True:
                    try:
                        calibrator.hear(sub.recv_multipart(zmq.NOBLOCK))
                    except zmq.Again:
                        break
            calibrator.step(pool, pub)
    return calibrator.published
