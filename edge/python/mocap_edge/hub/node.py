"""One sensor node as the hub sees it: what its heartbeats say, its clock on the hub's
(clock_fit.NodeClock, from its SyncReports), and its samples — an `ImuQuat` and the
`ImuAccel` the node sends right after it make one sample, timed on the hub's clock.

A sample's time is the node's 16 low bits of its timer (proto/can/README.md, "Samples"): of
the node times with those low bits, the hub takes the latest one not after the frame's
arrival mapped onto the node's clock, then maps it to the hub's clock. Until the node's clock
is fitted (its first two SyncReports), its samples cannot be timed and are counted
`unsynced`. Samples lost are counted from the 8-bit counter, its wraps resolved by the sample
times and the node's rate.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap_edge.hub.can_db import STATES
from mocap_edge.hub.clock_fit import NodeClock

LOW_BITS = 1 << 16  # ImuAccel.sample_time_us
SEQ = 1 << 8  # ImuQuat.seq, ImuAccel's pairing


@dataclasses.dataclass
class Sample:
    """One sample on the hub's clock: orientation w, x, y, z (unit), specific force (m/s²)."""
    time_ns: int
    quaternion: tuple[float, float, float, float]
    acceleration: tuple[float, float, float]
    orientation_invalid: bool
    acc_clipped: bool
    counter: int  # the node's sample counter, unwrapped


@dataclasses.dataclass
class NodeCounts:
    samples: int = 0
    lost: int = 0  # gaps in the sample counter
    unpaired: int = 0  # an ImuQuat without its ImuAccel, or the reverse (lost, duplicated or reordered)
    unsynced: int = 0  # samples before the node's clock was fitted
    late: int = 0  # samples that reached the hub more than the hub's late_ms after they were taken
    heartbeats: int = 0
    reboots: int = 0  # the node rebooted (its heartbeat went back to the boot state)
    clock_restarts: int = 0  # its clock fit started again (its timer jumped: a reboot missed by heartbeats)


class Node:
    def __init__(self, node_id: int, name: str, clock_window_s: float = 10.0):
        self.id, self.name = node_id, name
        self.clock = NodeClock(clock_window_s)
        self.counts = NodeCounts()
        self.heartbeat: dict | None = None  # the latest heartbeat's signals
        self.reply: dict | None = None  # the latest CommandReply's signals
        self.last_heard_ns: int | None = None
        self.last_sample_ns: int | None = None  # arrival of the frame that completed its latest sample
        self._quat: tuple[int, dict] | None = None  # (seq, signals) waiting for its ImuAccel
        self._counter: int | None = None  # the last sample's counter, unwrapped
        self._last_time_ns: int | None = None

    @property
    def state(self) -> str:
        return "unknown" if self.heartbeat is None else STATES.get(int(self.heartbeat["state"]), "fault")

    @property
    def rate_hz(self) -> float:
        return float(self.heartbeat["rate_hz"]) if self.heartbeat and self.heartbeat["rate_hz"] > 0 else 0.0

    def on_heartbeat(self, signals: dict, arrival_ns: int) -> None:
        rebooted = self.heartbeat is not None and signals["state"] == 0 and self.heartbeat["state"] != 0
        self.heartbeat, self.last_heard_ns = signals, arrival_ns
        self.counts.heartbeats += 1
        if rebooted:  # its timer and sample counter start again
            self.counts.reboots += 1
            self.clock = NodeClock(self.clock.window_ns / 1e9)
            self._counter = self._last_time_ns = None

    def on_sync_report(self, sync_tx_ns: int, rx_time_us: int, arrival_ns: int) -> None:
        restarts = self.clock.stats.restarts
        self.clock.add_pair(sync_tx_ns, rx_time_us)
        self.counts.clock_restarts += self.clock.stats.restarts - restarts
        self.last_heard_ns = arrival_ns

    def on_quat(self, signals: dict, arrival_ns: int) -> None:
        if self._quat is not None:
            self.counts.unpaired += 1
        self._quat = (int(signals["seq"]), signals)
        self.last_heard_ns = arrival_ns

    def on_accel(self, signals: dict, arrival_ns: int) -> Sample | None:
        """The sample this ImuAccel completes, or None (unpaired, or not timed yet: counted)."""
        self.last_heard_ns = arrival_ns
        quat, self._quat = self._quat, None
        if quat is None:
            self.counts.unpaired += 1
            return None
        now_us = self.clock.to_node_us(arrival_ns) if self.clock.fitted else None
        if now_us is None:
            self.counts.unsynced += 1
            return None
        low = int(signals["sample_time_us"])
        node_us = np.floor(now_us) - ((int(np.floor(now_us)) - low) % LOW_BITS)
        time_ns = self.clock.map_sample(node_us)
        self.last_sample_ns = arrival_ns
        return self._sample(quat, signals, time_ns)

    def _sample(self, quat: tuple[int, dict], accel: dict, time_ns: int) -> Sample:
        seq, q = quat
        counter = self._unwrap_counter(seq, time_ns)
        w, x, y, z = (q[k] for k in ("q_w", "q_x", "q_y", "q_z"))
        norm = float(np.sqrt(w * w + x * x + y * y + z * z)) or 1.0
        self.counts.samples += 1
        return Sample(time_ns, (w / norm, x / norm, y / norm, z / norm),
                      (accel["a_x"], accel["a_y"], accel["a_z"]), bool(accel["orientation_invalid"]),
                      bool(accel["acc_clipped"]), counter)

    def _unwrap_counter(self, seq: int, time_ns: int) -> int:
        """The counter unwrapped: the step mod 256 plus the wraps that the time gap at the node's
        rate says passed; counts the samples lost."""
        if self._counter is None:
            self._counter, self._last_time_ns = seq, time_ns
            return seq
        step = (seq - self._counter) % SEQ
        if self.rate_hz > 0 and self._last_time_ns is not None:
            expected = (time_ns - self._last_time_ns) * 1e-9 * self.rate_hz
            step += SEQ * max(0, int(round((expected - step) / SEQ)))
        self.counts.lost += max(0, step - 1)
        self._counter += step
        self._last_time_ns = time_ns
        return self._counter
