"""The simulated studio's IMUs as sensor nodes: node n of hub.toml plays the stream file's
(mocap_edge.streams) sensor named there. Each node has its own timer (sim.clock: ±100 ppm
and a random walk, seeded), answers the hub's Syncs and Commands, sends a heartbeat every
second and, once the hub has started it, each of its sensor's samples at its time (the take's
start + the stream's), quantised as the CAN database quantises them.

`StudioNodes` is driven in real time (sim.socketcand serves it to a live hub) and
`studio_batches` runs the same nodes and the hub's own code on a simulated bus at once (the
messages the hub would publish, for calibrating and testing without waiting for real time).
"""

from __future__ import annotations

import numpy as np
from mocap.net import wire

from mocap_edge.errors import EdgeError
from mocap_edge.hub.config import HubConfig
from mocap_edge.hub.hub import Hub
from mocap_edge.hub.sim.bus import BusConditions, SimulatedBus, make_nodes
from mocap_edge.streams import Streams

HEARTBEAT_NS = 1_000_000_000
LEAD_NS = 10_000_000_000  # the offline hub's Syncs before the take: its clock fits settled (p99 ~25 µs)
FrameOut = tuple[int, bytes]  # (frame id, data) a node sends


def studio_config(streams: Streams, hub_id: str = "hub0") -> HubConfig:
    """hub.toml for the simulated studio: node k + 1 is the stream file's sensor k, at its rate;
    25 Syncs a second (sample times within 0.13 ms p99 from the third second, 0.03 ms after
    ten, `make bench`: ample at video rate), not the default 100 — on the studio's two shared
    cores every CAN frame costs the simulated nodes and the hub, and 100 Syncs/s from 13 nodes
    are a third of the frames."""
    return HubConfig({k + 1: name for k, name in enumerate(streams.imu_ids)}, hub_id=hub_id,
                     rate_hz=stream_rate_hz(streams), sync_hz=25.0)


def stream_rate_hz(streams: Streams) -> int:
    """The stream file's IMU rate (whole Hz, as the nodes are configured); EdgeError when its
    samples are not evenly spaced at one."""
    steps = np.diff(streams.imu_times_ns)
    if len(steps) == 0 or steps.min() <= 0:
        raise EdgeError("the stream file has fewer than two IMU samples, or their times do not increase")
    rate = 1e9 / np.median(steps)
    if abs(rate - round(rate)) > 1e-6 * rate or np.ptp(steps) > 1000:
        raise EdgeError(f"the stream file's IMU samples are not evenly spaced at a whole rate ({rate:.4f} Hz)")
    return int(round(rate))


def _sensor_indices(streams: Streams, config: HubConfig) -> dict[int, int]:
    """node id -> the stream's sensor index; EdgeError when hub.toml names a sensor the stream
    lacks or its rate is not the stream's."""
    if config.rate_hz != stream_rate_hz(streams):
        raise EdgeError(f"hub.toml's rate_hz {config.rate_hz} is not the stream file's IMU rate "
                        f"{stream_rate_hz(streams)} Hz")
    missing = sorted(set(config.names.values()) - set(streams.imu_ids))
    if missing:
        raise EdgeError(f"hub.toml names sensors the stream file does not have: {', '.join(missing)}")
    return {node: streams.imu_ids.index(name) for node, name in config.names.items()}


class StudioNodes:
    """The nodes of hub.toml playing a stream file from start_ns (the hub's clock). Nodes start
    idle (until the hub's Command start). unplugged (sensor, from_s, to_s): that node's frames
    do not reach the bus during the span of the take; it samples on (its counter runs)."""

    def __init__(self, streams: Streams, config: HubConfig, start_ns: int, now_ns: int, seed: int = 0,
                 unplugged: tuple[str, float, float] | None = None):
        self.streams, self.start_ns, self.unplugged = streams, start_ns, unplugged
        self.sensor = _sensor_indices(streams, config)
        self.nodes = make_nodes(sorted(self.sensor), np.random.default_rng(seed), config.rate_hz,
                                BusConditions(), origin_ns=now_ns, running=False)
        self._index = 0  # the next stream sample
        self._next_heartbeat = now_ns

    def on_frame(self, frame_id: int, data: bytes, now_ns: int) -> list[FrameOut]:
        """What the nodes answer a frame from the hub with (received at now_ns)."""
        return [out for node in self.nodes.values() if not self._unplugged(node.id, now_ns)
                for out in node.on_frame(frame_id, data, now_ns)]

    def due(self, now_ns: int) -> list[FrameOut]:
        """The frames due by now_ns: heartbeats, and the samples taken by then."""
        out: list[FrameOut] = []
        if now_ns >= self._next_heartbeat:
            out += [node.heartbeat(now_ns) for node in self.nodes.values() if not self._unplugged(node.id, now_ns)]
            self._next_heartbeat += HEARTBEAT_NS
        times = self.streams.imu_times_ns
        while self._index < len(times) and self.start_ns + int(times[self._index]) <= now_ns:
            out += self._sample(self._index)
            self._index += 1
        return out

    def next_due_ns(self) -> int:
        times = self.streams.imu_times_ns
        sample = self.start_ns + int(times[self._index]) if self._index < len(times) else self._next_heartbeat
        return min(sample, self._next_heartbeat)

    def _unplugged(self, node_id: int, t_ns: int) -> bool:
        if self.unplugged is None or self.streams.imu_ids[self.sensor[node_id]] != self.unplugged[0]:
            return False
        return self.unplugged[1] <= (t_ns - self.start_ns) * 1e-9 < self.unplugged[2]

    def _sample(self, i: int) -> list[FrameOut]:
        t = self.start_ns + int(self.streams.imu_times_ns[i])
        out = []
        for node in self.nodes.values():
            if not node.running:
                continue
            k = self.sensor[node.id]
            frames = node.sample(t, self.streams.imu_quaternions[i, k], self.streams.imu_accelerations[i, k])
            if not self._unplugged(node.id, t):
                out += frames
        return out


def studio_batches(streams: Streams, start_ns: int, config: HubConfig | None = None,
                   seed: int = 0) -> list[wire.ImuBatch]:
    """The ImuBatch messages the hub publishes for the stream file played from start_ns, made at
    once: the nodes (running from the start, their clocks fitted from Syncs that began LEAD_NS
    before the take, as a hub runs before a take starts) and the hub's decode, clock fit and batching on a simulated bus (sim.bus:
    queuing, lost Syncs). Each batch's send_time_ns is the end of its batch period."""
    config = config or studio_config(streams)
    sensor = _sensor_indices(streams, config)
    hub = Hub(config)
    nodes = make_nodes(sorted(sensor), np.random.default_rng(seed), config.rate_hz, origin_ns=-LEAD_NS - 1_000_000_000)
    times, period_ns = streams.imu_times_ns, 1e9 / config.rate_hz

    def motion(node: int, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        i = int(round((t_s * 1e9 - times[0]) / period_ns))  # evenly spaced: stream_rate_hz checked it
        return streams.imu_quaternions[i, sensor[node]], streams.imu_accelerations[i, sensor[node]]

    bus = SimulatedBus(hub, nodes, BusConditions(sync_hz=config.sync_hz), motion, seed)
    # The bus runs on the take's clock (0: its start), shifted onto the shared timebase after.
    end_s = (int(times[-1]) + 2 * int(config.batch_ms * 1e6)) * 1e-9
    bus.run(-LEAD_NS * 1e-9, end_s, config.batch_ms, sample_times_ns=times)
    for batch in bus.batches:
        batch.send_time_ns += start_ns
        for s in batch.samples:
            s.sample_time_ns += start_ns
    return bus.batches
