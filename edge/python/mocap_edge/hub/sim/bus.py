"""Simulated nodes and the hub on one simulated CAN bus, in simulated time: the hub's Syncs
(delayed by queuing, some lost), the nodes' SyncReports, heartbeats and samples, each frame
reaching the hub after its transmission time — for the hub's tests and its benchmark, with no
dependence on the test machine's timing.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from mocap_edge.hub.can_db import Database
from mocap_edge.hub.clock_fit import WRAP_US
from mocap_edge.hub.hub import Hub
from mocap_edge.hub.sim.clock import NodeOscillator
from mocap_edge.hub.sim.node import SimulatedNode

FRAME_NS = 140_000  # an 8-byte classic frame at 1 Mbit/s, stuffing included
Motion = Callable[[int, float], tuple[np.ndarray, np.ndarray]]  # (node id, t s) -> (w, x, y, z), acceleration


def still(node: int, t: float) -> tuple[np.ndarray, np.ndarray]:
    return np.array([1.0, 0, 0, 0]), np.array([0, 0, 9.81])


@dataclasses.dataclass
class BusConditions:
    sync_hz: float = 50.0
    sync_delay_us: float = 500.0  # queuing before a Sync leaves, uniform 0..this
    sync_lost: float = 0.01  # fraction of Syncs no node receives
    ppm: float = 100.0  # node clock rate errors, uniform ±this
    walk_ppm_per_sqrt_s: float = 0.1


def make_nodes(ids: list[int], rng: np.random.Generator, rate_hz: int = 60,
               conditions: BusConditions = BusConditions(), origin_ns: int = 0,
               running: bool = True) -> dict[int, SimulatedNode]:
    """Nodes with clocks off by up to ±conditions.ppm, timers started anywhere, at origin_ns;
    running, or idle until a hub starts them."""
    db = Database(checked=False)  # the nodes clip their values into the signals' ranges
    return {i: SimulatedNode(i, NodeOscillator(rng.uniform(-conditions.ppm, conditions.ppm), rng.uniform(0, WRAP_US),
                                               conditions.walk_ppm_per_sqrt_s, rng, origin_ns), rate_hz, db,
                          running)
            for i in ids}


class SimulatedBus:
    """Runs a hub and simulated nodes from `start_s` to `end_s`; `silent` (node id -> [(from s,
    to s)]) unplugs a node for those spans. Frames are handed to the hub in arrival order, and
    a batch taken when a round is complete or a batch period ends (mocap_edge.hub.service)."""

    def __init__(self, hub: Hub, nodes: dict[int, SimulatedNode], conditions: BusConditions = BusConditions(),
                 motion: Motion = still, seed: int = 0):
        self.hub, self.nodes, self.c, self.motion = hub, nodes, conditions, motion
        self.rng = np.random.default_rng(seed)
        self.silent: dict[int, list[tuple[float, float]]] = {}
        self.truth: list[tuple[int, int, int]] = []  # (node id, sample counter, true time ns) of every sample sent
        self.batches: list = []
        self._sync_seq = 0

    def run(self, start_s: float, end_s: float, batch_ms: float = 10.0, sample_times_ns=None) -> None:
        """sample_times_ns: when the nodes sample (ns on the bus's clock), instead of every
        1 / rate from start_s."""
        events = self._syncs(start_s, end_s) + self._samples(start_s, end_s, sample_times_ns) + \
            self._heartbeats(start_s, end_s)
        events.sort(key=lambda e: e[0])
        next_batch = int(start_s * 1e9) + int(batch_ms * 1e6)
        for arrival, frame_id, data in events:
            while arrival >= next_batch:
                batch = self.hub.take_batch(next_batch)
                if batch is not None:
                    self.batches.append(batch)
                next_batch += int(batch_ms * 1e6)
            if frame_id is None:  # the hub's own Sync: (tx time, None, sequence)
                self.hub.sync_sent(data, arrival)
            else:
                self.hub.on_frame(arrival, frame_id, data)
                if self.hub.round_complete(arrival):  # as the hub's service does
                    self.batches.append(self.hub.take_batch(arrival))

    def _quiet(self, node: int, t: float) -> bool:
        return any(a <= t < b for a, b in self.silent.get(node, []))

    def _syncs(self, start_s: float, end_s: float) -> list:
        out = []
        for t in np.arange(start_s, end_s, 1 / self.c.sync_hz):
            tx = int(t * 1e9)
            seq, self._sync_seq = self._sync_seq, (self._sync_seq + 1) % 256
            out.append((tx, None, seq))
            if self.rng.random() < self.c.sync_lost:
                continue
            # The hub's transmit stamp and the node's receive stamp both mark the frame's end:
            # only the queuing before it left differs.
            on_bus = tx + int(self.rng.uniform(0, self.c.sync_delay_us) * 1e3)
            sync = self.hub.db.sync(seq)
            for k, node in enumerate(self.nodes.values()):
                if self._quiet(node.id, t):
                    continue
                for frame_id, data in node.on_frame(*sync, on_bus):
                    out.append((on_bus + (k + 1) * FRAME_NS, frame_id, data))
        return out

    def _samples(self, start_s: float, end_s: float, sample_times_ns=None) -> list:
        out = []
        for node in self.nodes.values():
            if sample_times_ns is None:
                times = [int(t * 1e9) for t in np.arange(start_s, end_s, 1 / node.rate_hz)]
            else:
                times = [int(t) for t in sample_times_ns if start_s * 1e9 <= t < end_s * 1e9]
            for true_ns in times:
                if not node.running:
                    continue
                t = true_ns * 1e-9
                q, a = self.motion(node.id, t)
                frames = node.sample(true_ns, q, a)  # an unplugged node samples on, unheard
                if self._quiet(node.id, t):
                    continue
                self.truth.append((node.id, (node.seq - 1) % 256, true_ns))
                sent = true_ns + int(self.rng.uniform(0, 2e6))  # the node's transmit queue: < 2 ms
                out += [(sent + k * FRAME_NS, fid, data) for k, (fid, data) in enumerate(frames)]
        return out

    def _heartbeats(self, start_s: float, end_s: float) -> list:
        out = []
        for node in self.nodes.values():
            for t in np.arange(start_s + 0.3, end_s, 1.0):
                if not self._quiet(node.id, t):
                    out.append((int(t * 1e9) + FRAME_NS, *node.heartbeat(int(t * 1e9))))
        return out
