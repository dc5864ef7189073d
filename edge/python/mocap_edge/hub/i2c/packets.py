"""FIFO packet 3 (16 bytes: header, accel x y z, gyro x y z as big-endian int16, temperature,
timestamp) to samples in SI units, float32 as the firmware's icm42688_convert computes them.

Three kinds of invalid packet, each counted: an *empty* header (HEADER_MSG: no sample, takes
no sample slot), an *unexpected* header (not packet 3: the stream is misaligned; parsing stops
there and the caller flushes the FIFO, as the firmware does), and a packet with a -32768 value
(a sensor without data yet: a sample slot, but no data).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap_edge.hub.i2c import regs

CLIP_LSB = 32767


@dataclasses.dataclass
class Packets:
    """The samples of a read that take a slot in time, oldest first."""
    raw: np.ndarray  # (n, 6) int16 accel x y z, gyro x y z
    acc_mps2: np.ndarray  # (n, 3) float32, sensor frame, gravity included
    gyr_rads: np.ndarray  # (n, 3) float32
    valid: np.ndarray  # (n,) bool: no -32768 value
    acc_clipped: np.ndarray  # (n,) bool: an accelerometer axis at full scale
    empty: int = 0  # packets with the empty header (no slot)
    corrupt: bool = False  # an unexpected header: parsing stopped there


def parse(data: bytes, acc_mps2_per_lsb: np.float32, gyr_rads_per_lsb: np.float32) -> Packets:
    """The packets of `data` (whole packets) up to the first unexpected header."""
    table = np.frombuffer(data, np.uint8).reshape(-1, regs.FIFO_PACKET_BYTES)
    header = table[:, 0]
    empty = (header & regs.FIFO_HEADER_EMPTY) != 0
    bad = ~empty & ((header & regs.FIFO_HEADER_KIND_MASK) != regs.FIFO_HEADER_PACKET3)
    end = int(np.argmax(bad)) if bad.any() else len(table)
    keep = table[:end][~empty[:end]]
    raw = np.ascontiguousarray(keep[:, 1:13]).view(">i2").astype(np.int16).reshape(-1, 6)
    counts = raw.astype(np.float32)
    return Packets(raw=raw, acc_mps2=counts[:, :3] * acc_mps2_per_lsb, gyr_rads=counts[:, 3:] * gyr_rads_per_lsb,
                   valid=~(raw == regs.RAW_INVALID).any(axis=1), acc_clipped=(np.abs(counts[:, :3]) >= CLIP_LSB).any(axis=1),
                   empty=int(empty[:end].sum()), corrupt=bool(bad.any()))
