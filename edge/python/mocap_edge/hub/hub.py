"""The hub's work between the CAN bus and the publisher, without either: each frame decoded
and checked, nodes discovered from their heartbeats, each node's clock fitted from the Syncs
the hub sent and the SyncReports it got back, samples paired and timed on the hub's clock,
and handed over as one ImuBatch per batch period. Every bad frame is counted and dropped.

hub.toml names the nodes (node id -> the session's sensor name); a node that is not named
there is discovered and reported, and its samples are dropped (counted `unnamed`): the host
would not know what body segment they measure.
"""

from __future__ import annotations

import collections

import numpy as np

from mocap.net import wire
from mocap_edge.hub.bus_errors import BusErrors
from mocap_edge.hub.can_db import CanFrameError, Database
from mocap_edge.hub.config import HubConfig
from mocap_edge.hub.node import Node, Sample

STATUS_ORIENTATION_INVALID = wire.ImuSample.STATUS_ORIENTATION_INVALID
STATUS_ACCELERATION_CLIPPED = wire.ImuSample.STATUS_ACCELERATION_CLIPPED


class Hub:
    def __init__(self, config: HubConfig, db: Database | None = None):
        self.config, self.db = config, db or Database()
        self.nodes: dict[int, Node] = {}
        self.dropped: collections.Counter[str] = collections.Counter()
        self._syncs: dict[int, int] = {}  # sync_seq -> the hub's transmit time
        self._pending: list[wire.ImuSample] = []
        self._waiting: set[int] = set()  # nodes with a sample in _pending
        self._delays: dict[int, list[int]] = {}  # node id -> arrival - sample time since the last Health
        self._sequence = 0
        self.frames = 0  # frames received
        self._health_ns: int | None = None  # the previous Health report's time
        self._reported: dict[int, int] = {}  # node id -> its samples at the previous report

    def sync_sent(self, sequence: int, tx_ns: int) -> None:
        """A Sync left at tx_ns (the hub's clock: the frame's transmit timestamp)."""
        self._syncs[sequence % 256] = tx_ns

    def on_frame(self, arrival_ns: int, frame_id: int, data: bytes, extended: bool = False,
                 remote: bool = False) -> bool:
        """One frame received at arrival_ns; False when it was dropped (counted by reason)."""
        self.frames += 1
        try:
            frame = self.db.decode(frame_id, data, extended, remote)
        except CanFrameError as e:
            self.dropped[e.reason] += 1
            return False
        node = self.nodes.get(frame.node)
        if node is None:
            node = self.nodes[frame.node] = Node(frame.node, self.config.names.get(frame.node, ""))
        handler = getattr(self, f"_on_{frame.name}")
        return handler(node, frame.signals, arrival_ns)

    def round_complete(self, now_ns: int) -> bool:
        """Every named node that is sampling (a sample arrived within its last 3 periods) has a
        sample waiting: the nodes sample together, so the round's batch can leave now rather
        than at the end of the batch period."""
        if not self._waiting:
            return False
        for node in self.nodes.values():
            if (node.name and node.last_sample_ns is not None and node.id not in self._waiting and node.rate_hz > 0
                    and now_ns - node.last_sample_ns < 3e9 / node.rate_hz):
                return False
        return True

    @property
    def pending(self) -> tuple[wire.ImuSample, ...]:
        """The samples waiting for the next batch, oldest first."""
        return tuple(self._pending)

    def add_samples(self, samples: list[wire.ImuSample]) -> None:
        """Samples timed elsewhere (the hub's I2C IMUs), for the next batch."""
        self._pending.extend(samples)

    def take_batch(self, now_ns: int) -> wire.ImuBatch | None:
        """The samples timed since the last batch, as one ImuBatch sent at now_ns (None: none)."""
        if not self._pending:
            return None
        batch = wire.ImuBatch(hub_id=self.config.hub_id, sequence=self._sequence, send_time_ns=now_ns)
        batch.samples.extend(self._pending)
        self._pending, self._sequence = [], self._sequence + 1
        self._waiting.clear()
        return batch

    def stale(self, now_ns: int) -> list[Node]:
        """Named nodes silent for stale_s (never heard: stale from the start)."""
        limit = int(self.config.stale_s * 1e9)
        heard = {n.id: n.last_heard_ns for n in self.nodes.values()}
        return [self.nodes.get(i) or Node(i, name) for i, name in self.config.names.items()
                if heard.get(i) is None or now_ns - heard[i] > limit]

    def health(self, now_ns: int, bus: BusErrors | None = None) -> wire.Health:
        """The hub's Health (source: its id): per named node "imu/<sensor>" (active unless
        stale; samples per second since the previous report; samples, losses, unpaired frames
        as duplicates, samples that reached the hub more than late_ms after they were taken as
        late, that delay's p50 / p99 over the period, the clock fit's residual) and "bus"
        (frames received, bad frames as malformed, bus errors, bus-off and recoveries)."""
        health = wire.Health(source=self.config.hub_id, time_ns=now_ns)
        period_s = (now_ns - self._health_ns) * 1e-9 if self._health_ns is not None else 0.0
        stale = {n.id for n in self.stale(now_ns)}
        for node_id, name in sorted(self.config.names.items()):
            node = self.nodes.get(node_id) or Node(node_id, name)
            c = node.counts
            rate = (c.samples - self._reported.get(node_id, 0)) / period_s if period_s > 0 else 0.0
            self._reported[node_id] = c.samples
            delays = np.array(self._delays.pop(node_id, [np.nan])) * 1e-6
            health.streams.add(stream=f"imu/{name}", active=node_id not in stale, rate_hz=rate, received=c.samples,
                               dropped=c.unsynced + c.unpaired, duplicates=c.unpaired, lost=c.lost, late=c.late,
                               latency_p50_ms=float(np.percentile(delays, 50)),
                               latency_p99_ms=float(np.percentile(delays, 99)), clock_residual_us=node.clock.residual_us)
        bad = sum(self.dropped.values())
        bus = bus or BusErrors()
        health.streams.add(stream="bus", active=True, received=self.frames, malformed=bad, dropped=bad,
                           bus_errors=bus.total(), bus_off=bus.counts["bus_off"],
                           bus_recoveries=bus.counts["recoveries"])
        self._health_ns = now_ns
        return health

    def _on_Heartbeat(self, node: Node, signals: dict, arrival_ns: int) -> bool:
        node.on_heartbeat(signals, arrival_ns)
        return True

    def _on_SyncReport(self, node: Node, signals: dict, arrival_ns: int) -> bool:
        tx = self._syncs.get(int(signals["sync_seq"]))
        if tx is None or arrival_ns - tx > 1_000_000_000:  # not a Sync of ours, or one from long ago
            self.dropped["sync_unknown"] += 1
            return False
        node.on_sync_report(tx, int(signals["rx_time_us"]), arrival_ns)
        return True

    def _on_ImuQuat(self, node: Node, signals: dict, arrival_ns: int) -> bool:
        node.on_quat(signals, arrival_ns)
        return True

    def _on_ImuAccel(self, node: Node, signals: dict, arrival_ns: int) -> bool:
        sample = node.on_accel(signals, arrival_ns)
        if sample is None:
            return False
        if not node.name:
            self.dropped["unnamed"] += 1
            return False
        self._pending.append(_wire_sample(node.name, sample))
        delay = arrival_ns - sample.time_ns
        self._delays.setdefault(node.id, []).append(delay)
        node.counts.late += delay > self.config.late_ms * 1e6
        self._waiting.add(node.id)
        return True

    def _on_CommandReply(self, node: Node, signals: dict, arrival_ns: int) -> bool:
        node.last_heard_ns = arrival_ns
        node.reply = signals
        return True


def _wire_sample(name: str, s: Sample) -> wire.ImuSample:
    status = (STATUS_ORIENTATION_INVALID if s.orientation_invalid else 0) | \
        (STATUS_ACCELERATION_CLIPPED if s.acc_clipped else 0)
    w, x, y, z = s.quaternion
    ax, ay, az = s.acceleration
    return wire.ImuSample(sensor_id=name, sample_time_ns=s.time_ns, qw=w, qx=x, qy=y, qz=z, ax=ax, ay=ay, az=az,
                          status=status, packet_counter=s.counter % 65536)
