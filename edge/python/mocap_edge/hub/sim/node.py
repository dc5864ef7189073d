"""A sensor node's side of the CAN protocol in software, for the hub's tests and the simulated
studio: its own timer (sim.clock.NodeOscillator: offset, rate error, random walk), the
SyncReport it answers each Sync with (the Sync's arrival on that timer), its heartbeats,
its replies to commands, and its samples quantised as the CAN database quantises them.
The frames are those the firmware sends (proto/can/README.md); `true_ns` is the instant on
the hub's clock at which the node does a thing.
"""

from __future__ import annotations

import math

import numpy as np

from mocap_edge.hub.can_db import COMMANDS, Database
from mocap_edge.hub.clock_fit import WRAP_US
from mocap_edge.hub.node import LOW_BITS, SEQ
from mocap_edge.hub.sim.clock import NodeOscillator

Q_MAX = 8191 / 8192  # the largest quaternion component the 14-bit signals carry
A_MAX = 255.984375  # m/s², the 15-bit signals' largest
STATE_CODES = {"boot": 0, "idle": 1, "running": 2, "fault": 3}


class SimulatedNode:
    def __init__(self, node_id: int, oscillator: NodeOscillator, rate_hz: int = 60, db: Database | None = None,
                 running: bool = True):
        self.id, self.osc, self.db = node_id, oscillator, db or Database()
        self.rate_hz, self.running, self.state = rate_hz, running, "running" if running else "idle"
        self.acc_range_g, self.gyro_range_dps, self.mode = 16, 2000, 0
        self.seq = 0
        self.synced_at_ns: int | None = None
        self._sync_id, self._command_id = self.db.sync(0)[0], self.db.command(node_id, "start")[0]

    def on_frame(self, frame_id: int, data: bytes, true_ns: int) -> list[tuple[int, bytes]]:
        """The frames the node answers a frame from the hub with (received at true_ns)."""
        if frame_id == self._sync_id:
            self.synced_at_ns = true_ns
            rx_us = int(np.floor(self.osc.advance(true_ns))) % WRAP_US
            return [self.db.encode("SyncReport", self.id, sync_seq=data[0], rx_time_us=rx_us)]
        if frame_id == self._command_id:
            return [self._command(data)]
        return []

    def sample(self, true_ns: int, quaternion, acceleration, orientation_invalid: bool = False) -> list[tuple[int, bytes]]:
        """An ImuQuat and its ImuAccel for a sample taken at true_ns (quaternion w, x, y, z).
        Plain floats, not numpy: the simulated studio's nodes send 1,300 samples a second."""
        w, x, y, z = (float(v) for v in quaternion)
        scale = (1.0 if w >= 0 else -1.0) / math.sqrt(w * w + x * x + y * y + z * z)  # w >= 0 is sent
        q = [min(max(v * scale, -1.0), Q_MAX) for v in (w, x, y, z)]
        a = [float(v) for v in acceleration]
        node_us = math.floor(self.osc.advance(true_ns))
        quat = self.db.encode("ImuQuat", self.id, q_w=q[0], q_x=q[1], q_y=q[2], q_z=q[3], seq=self.seq)
        clipped = max(abs(v) for v in a) > A_MAX
        a = [min(max(v, -256.0), A_MAX) for v in a]
        accel = self.db.encode("ImuAccel", self.id, a_x=a[0], a_y=a[1], a_z=a[2],
                               orientation_invalid=int(orientation_invalid), acc_clipped=int(clipped),
                               mag_disturbed=0, sample_time_us=node_us % LOW_BITS)
        self.seq = (self.seq + 1) % SEQ
        return [quat, accel]

    def heartbeat(self, true_ns: int) -> tuple[int, bytes]:
        synced = self.synced_at_ns is not None and true_ns - self.synced_at_ns < 2_000_000_000
        flags = dict.fromkeys(("imu_nack", "mag_nack", "fifo_overflow", "imu_stuck", "mag_stuck", "command_refused",
                               "frame_malformed", "self_test_failed", "acc_clipped", "mag_disturbed",
                               "tx_overflow"), 0)
        return self.db.encode("Heartbeat", self.id, state=STATE_CODES[self.state], mode=self.mode, synced=int(synced),
                              chip=1, rate_hz=self.rate_hz, fw_version_major=1, fw_version_minor=0, error_count=0,
                              **flags)

    def reboot(self, oscillator: NodeOscillator) -> None:
        """The node restarts: a new timer, its counter from 0, boot state until it runs again."""
        self.osc, self.seq, self.state, self.synced_at_ns = oscillator, 0, "boot", None

    def _command(self, data: bytes) -> tuple[int, bytes]:
        code = data[0]
        result = 0
        if code == COMMANDS["start"]:
            self.running, self.state = True, "running"
        elif code == COMMANDS["stop"]:
            self.running, self.state = False, "idle"
        elif code == COMMANDS["set_rate"]:
            rate = int.from_bytes(data[1:3], "little")
            result = 4 if self.running else 3 if not 1 <= rate <= 400 else 0
            self.rate_hz = rate if result == 0 else self.rate_hz
        elif code == COMMANDS["set_ranges"]:
            acc, gyro = data[1], int.from_bytes(data[2:4], "little")
            result = 4 if self.running else 3 if acc not in (2, 4, 8, 16) or gyro not in (250, 500, 1000, 2000) else 0
            if result == 0:
                self.acc_range_g, self.gyro_range_dps = acc, gyro
        elif code == COMMANDS["set_mode"]:
            result = 3 if data[1] > 1 else 0
            self.mode = data[1] if result == 0 else self.mode
        else:
            result = 1
        return self.db.encode("CommandReply", self.id, command=code, result=result, rate_hz=self.rate_hz,
                              acc_range_g=self.acc_range_g, gyro_range_dps=self.gyro_range_dps, mode=self.mode,
                              running=int(self.running))
