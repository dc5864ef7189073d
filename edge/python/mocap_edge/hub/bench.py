"""The hub's benchmark (`mocap bench --only hub`): frames decoded per second on one core, the
added latency from a sample's last frame reaching the hub to its ImuBatch leaving, and the
clock fit's sample-time error — all on the simulated bus (mocap_edge.hub.sim.bus), so the
figures do not depend on a CAN interface."""

from __future__ import annotations

import time

import numpy as np

from mocap_edge.hub.config import HubConfig
from mocap_edge.hub.hub import Hub
from mocap_edge.hub.sim.bus import BusConditions, SimulatedBus, make_nodes
from mocap_edge.hub.sim.clock import sample_errors_us

NODES = 17  # a saturated classic bus at 120 Hz (proto/can/README.md, "Bus load")


def decode_rate(seconds: float = 12.0) -> tuple[float, int]:
    """(frames per second, frames) of the hub's on_frame over a recorded simulated take of
    NODES nodes at 120 Hz: the bus is simulated first, then its frames are timed alone."""
    names = {i: f"s{i}" for i in range(1, NODES + 1)}
    recorder = _Recorder()
    bus = SimulatedBus(recorder, make_nodes(list(names), np.random.default_rng(0), 120), BusConditions(sync_hz=50))
    bus.run(0.0, seconds)
    hub = Hub(HubConfig(names))
    start = time.perf_counter()
    for k, (kind, args) in enumerate(recorder.calls):
        (hub.on_frame if kind == "frame" else hub.sync_sent)(*args)
        if k % 512 == 511:  # a batch every ~5 ms of a saturated bus
            hub.take_batch(args[0])
    elapsed = time.perf_counter() - start
    frames = sum(1 for kind, _ in recorder.calls if kind == "frame")
    return frames / elapsed, frames


def batch_latency_ms(seconds: float = 5.0, batch_ms: float = 10.0) -> float:
    """p99 of (batch leaves - the sample's ImuAccel reached the hub), ms, on the simulated bus."""
    names = {i: f"s{i}" for i in range(1, 14)}
    hub = _ArrivalHub(HubConfig(names))
    bus = SimulatedBus(hub, make_nodes(list(names), np.random.default_rng(1), 60))
    bus.run(0.0, seconds, batch_ms)
    waits = [(b.send_time_ns - hub.arrivals[(s.sensor_id, s.sample_time_ns)]) / 1e6
             for b in bus.batches for s in b.samples]
    return float(np.percentile(waits, 99))


def clock_errors(sync_hz: float, seeds: int = 10) -> dict:
    early, late = [], []
    for seed in range(seeds):
        t, e = sample_errors_us(seconds=11.0, sync_hz=sync_hz, seed=seed)
        early += list(e[(t >= 2) & (t < 3)])
        late += list(e[t >= 10])
    return {"sync_hz": sync_hz, "p99_us_2_to_3_s": round(float(np.percentile(early, 99)), 1),
            "p99_us_after_10_s": round(float(np.percentile(late, 99)), 1)}


def hub() -> dict:
    rate, frames = decode_rate()
    return {"bench": "hub", "frames_decoded_per_s": round(rate), "frames": frames,
            "batch_latency_p99_ms": round(batch_latency_ms(), 2), "batch_period_ms": 10.0,
            "clock": [clock_errors(hz) for hz in (25.0, 50.0, 100.0)],
            "conditions": "node clocks ±100 ppm + random walk, Syncs queued 0-0.5 ms, 1% lost"}


class _Recorder:
    """Stands in for a Hub on the simulated bus and keeps what it was given."""

    def __init__(self):
        from mocap_edge.hub.can_db import Database
        self.db, self.calls = Database(), []

    def on_frame(self, *args):
        self.calls.append(("frame", args))

    def sync_sent(self, *args):
        self.calls.append(("sync", args))

    def take_batch(self, now_ns):
        return None

    def round_complete(self, now_ns):
        return False


class _ArrivalHub(Hub):
    """A Hub that notes when each sample's last frame arrived."""

    def __init__(self, config):
        super().__init__(config)
        self.arrivals = {}

    def on_frame(self, arrival_ns, frame_id, data, extended=False, remote=False):
        before = len(self.pending)
        ok = super().on_frame(arrival_ns, frame_id, data, extended, remote)
        for s in self.pending[before:]:
            self.arrivals[(s.sensor_id, s.sample_time_ns)] = arrival_ns
        return ok
