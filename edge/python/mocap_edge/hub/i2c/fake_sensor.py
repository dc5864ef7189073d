"""The fake ICM-42688-P's sensor side (the register side is ``fake_chip``): its oscillator and
ODR ticks, sampling a motion and quantising it at the configured ranges, the FIFO (packet 3,
stream mode, 128 packets, the oldest dropped and counted when full), and the record of the
true instant of every sample, which tests compare the driver's times with.

As firmware/tests/support/fake_icm42688_sensor.c: the ODR runs ``clock_error`` fast on the
fake's clock (+0.02: 2 % fast); the gyroscope reads -32768 for 30 ms after it is powered;
``stuck`` repeats the last sample; ``noise_lsb`` adds Gaussian noise (a real chip's is a few
LSB, so its raw samples never repeat).
"""

from __future__ import annotations

import collections
import dataclasses
import math
from typing import Callable, Sequence

import numpy as np

from mocap_edge.hub.i2c import regs

GRAVITY_MPS2 = 9.80665
GYRO_START_NS = 30_000_000  # gyroscope invalid after power-on
LOG_SIZE = 200_000  # records of packets read out, kept for the test
# ODR code -> nominal period, ns (0: reserved)
PERIODS_NS = (0, 31_250, 62_500, 125_000, 250_000, 500_000, 1_000_000, 5_000_000, 10_000_000,
              20_000_000, 40_000_000, 80_000_000, 160_000_000, 320_000_000, 640_000_000, 2_000_000)

Vector = Sequence[float]
Motion = Callable[[float], tuple[Vector, Vector]]  # t (s, fake clock) -> (gyr rad/s, acc m/s^2), sensor frame


@dataclasses.dataclass
class FakeRecord:
    """One sample as the chip took it: its true instant and the motion before quantisation."""
    sequence: int  # samples taken since the fake was made, 0-based
    time_ns: int  # true sampling instant on the fake's clock
    gyr_rads: tuple[float, float, float]
    acc_mps2: tuple[float, float, float]


def _still(_: float) -> tuple[Vector, Vector]:
    return (0.0, 0.0, 0.0), (0.0, 0.0, GRAVITY_MPS2)


class FakeSensor:
    """Samples at the ODR of `bank0` (the register side's bank 0, read live) into the FIFO."""

    def __init__(self, bank0: bytearray, motion: Motion | None, clock_error: float, noise_lsb: float,
                 seed: int):
        self.bank0 = bank0
        self.motion = motion or _still
        self.clock_error = clock_error
        self.noise_lsb = noise_lsb
        self.rng = np.random.default_rng(seed)
        self.stuck = False
        self.fifo: collections.deque[tuple[bytes, FakeRecord]] = collections.deque()
        self.lost_packets = 0  # FIFO_LOST_PKT
        self.dropped = 0  # packets that left the FIFO unread: overflowed or flushed
        self.int_status = 0
        self.sequence = 0
        self.read_log: collections.deque[FakeRecord] = collections.deque(maxlen=LOG_SIZE)
        self.raw = [0, 0, 0, 0, 0, 0]  # last accel x y z, gyro x y z
        self.gyro_valid_ns = 0
        self.chip_time_us = 0
        self._origin_ns, self._ticks, self._period_ns = 0, 0, 0.0  # tick n at origin + n * period

    def schedule(self, now_ns: int) -> None:
        """(Re)starts the ticks from now at the current ODR and power, or stops them."""
        power, code = self.bank0[regs.REG_PWR_MGMT0], self.bank0[regs.REG_GYRO_CONFIG0] & regs.CONFIG0_ODR_MASK
        on = (power & regs.PWR_MGMT0_GYRO_LN) == regs.PWR_MGMT0_GYRO_LN or (power & 0x03) >= 0x02
        nominal = PERIODS_NS[code]
        self._period_ns = nominal / (1.0 + self.clock_error) if on and nominal else 0.0
        self._origin_ns, self._ticks = now_ns, 0

    def power_changed(self, before: int, after: int, now_ns: int) -> None:
        gyro = regs.PWR_MGMT0_GYRO_LN
        if (after & gyro) == gyro and (before & gyro) != gyro:
            self.gyro_valid_ns = now_ns + GYRO_START_NS
        self.schedule(now_ns)

    def next_tick_ns(self) -> float:
        return self._origin_ns + (self._ticks + 1) * self._period_ns if self._period_ns else math.inf

    def advance_to(self, now_ns: int) -> None:
        """Takes every sample whose tick is at or before now."""
        while self.next_tick_ns() <= now_ns:
            self._ticks += 1
            self._take(int(round(self._origin_ns + self._ticks * self._period_ns)))

    def flush(self) -> None:
        self.dropped += len(self.fifo)
        self.fifo.clear()
        self.lost_packets = 0

    def _take(self, time_ns: int) -> None:
        gyr, acc = self.motion(time_ns * 1e-9)
        record = FakeRecord(self.sequence, time_ns, tuple(map(float, gyr)), tuple(map(float, acc)))
        if not (self.stuck and self.sequence > 0):
            self.raw = self._quantise(record)
        raw = list(self.raw)
        if time_ns < self.gyro_valid_ns:
            raw[3:] = [regs.RAW_INVALID] * 3
        self.int_status |= regs.INT_STATUS_DATA_RDY
        if self._fifo_enabled():
            self._push(self._packet(raw), record)
        self.chip_time_us += PERIODS_NS[self.bank0[regs.REG_GYRO_CONFIG0] & regs.CONFIG0_ODR_MASK] // 1000
        self.sequence += 1

    def _quantise(self, record: FakeRecord) -> list[int]:
        acc_fs = (self.bank0[regs.REG_ACCEL_CONFIG0] >> regs.CONFIG0_FS_SHIFT) & 0x03
        gyr_fs = (self.bank0[regs.REG_GYRO_CONFIG0] >> regs.CONFIG0_FS_SHIFT) & 0x03
        acc_lsb = regs.ACC_RANGES_G[acc_fs] * GRAVITY_MPS2 / 32768.0
        gyr_lsb = math.radians(regs.GYRO_RANGES_DPS[gyr_fs]) / 32768.0
        counts = [a / acc_lsb for a in record.acc_mps2] + [g / gyr_lsb for g in record.gyr_rads]
        if self.noise_lsb:
            counts = list(np.asarray(counts) + self.rng.normal(0.0, self.noise_lsb, 6))
        return [int(max(-32767, min(32767, round(c)))) for c in counts]

    def _fifo_enabled(self) -> bool:
        both = regs.FIFO_CONFIG1_ACCEL_EN | regs.FIFO_CONFIG1_GYRO_EN
        mode = self.bank0[regs.REG_FIFO_CONFIG] & regs.FIFO_CONFIG_MODE_MASK
        return mode == regs.FIFO_CONFIG_STREAM and (self.bank0[regs.REG_FIFO_CONFIG1] & both) == both

    def put16(self, value: int) -> bytes:
        big = self.bank0[regs.REG_INTF_CONFIG0] & regs.INTF_CONFIG0_DATA_BIG
        return (value & 0xFFFF).to_bytes(2, "big" if big else "little")

    def _packet(self, raw: list[int]) -> bytes:
        header = regs.FIFO_HEADER_PACKET3 | regs.FIFO_HEADER_TMST_ODR
        data = b"".join(self.put16(v) for v in raw)
        temp = 0  # 25 deg C
        return bytes([header]) + data + bytes([temp & 0xFF]) + self.put16(self.chip_time_us)

    def _push(self, packet: bytes, record: FakeRecord) -> None:
        if len(self.fifo) == regs.FIFO_CAPACITY_SAMPLES:  # full: the oldest is lost
            self.fifo.popleft()
            self.dropped += 1
            self.lost_packets = min(self.lost_packets + 1, 0xFFFF)
        self.fifo.append((packet, record))
        if len(self.fifo) == regs.FIFO_CAPACITY_SAMPLES:
            self.int_status |= regs.INT_STATUS_FIFO_FULL

    def fifo_level(self, read_offset: int) -> int:
        """FIFO_COUNT in its unit (packets with FIFO_COUNT_REC, else bytes)."""
        if self.bank0[regs.REG_INTF_CONFIG0] & regs.INTF_CONFIG0_FIFO_COUNT_REC:
            return len(self.fifo)
        return len(self.fifo) * regs.FIFO_PACKET_BYTES - read_offset
