"""How much of the CAN bus the sensor nodes take (docs/imu_bus.md), counted bit by bit with
worst-case stuffing, and the hub's limit: a configuration that would load the bus above
MAX_LOAD is refused (collisions back off, frames wait and sample times queue: a bus near
saturation delays the Syncs that time everything).

    python -m mocap_edge.hub.bus_budget      # prints the tables of docs/imu_bus.md
"""

from __future__ import annotations

import math

MAX_LOAD = 0.60
BITRATE = 1_000_000  # classic CAN, and CAN FD's arbitration phase
HEARTBEAT_HZ = 1.0


def classic_frame_bits(data_bytes: int) -> int:
    """A classic CAN 2.0A data frame, worst case: SOF, 11-bit id, RTR, IDE, r0, DLC (19 bits),
    data, CRC (15), CRC and ACK delimiters, ACK slot, EOF (7), 3 bits of interframe space — and
    one stuff bit per 4 of the 34 + 8n bits from SOF to the CRC that stuffing may need."""
    stuffed = 34 + 8 * data_bytes
    return 47 + 8 * data_bytes + (stuffed - 1) // 4


def fd_frame_us(data_bytes: int, data_bitrate: float) -> float:
    """A CAN FD frame (11-bit id, bit-rate switch), worst case, µs: the arbitration phase at
    BITRATE (SOF to BRS: 17 bits + 4 stuff; CRC delimiter, ACK, EOF, interframe space: 13) and
    the data phase at data_bitrate (ESI, DLC, data, stuff count (4), CRC 17 or 21 with its fixed
    stuff bits, and one dynamic stuff bit per 4 bits before the CRC)."""
    crc = 17 if data_bytes <= 16 else 21
    dynamic = 1 + 4 + 8 * data_bytes
    data_bits = dynamic + (dynamic - 1) // 4 + 4 + crc + math.ceil((crc + 4) / 4)
    return (17 + 4 + 13) / BITRATE * 1e6 + data_bits / data_bitrate * 1e6


def classic_load(nodes: int, rate_hz: float, sync_hz: float) -> float:
    """Fraction of a classic 1 Mbit/s bus: per sample an ImuQuat and an ImuAccel (8 bytes each),
    per Sync (1 byte) one SyncReport (5 bytes) from every node, a heartbeat (8 bytes) per node
    per second."""
    per_second = (nodes * rate_hz * 2 * classic_frame_bits(8) + sync_hz * (classic_frame_bits(1)
                  + nodes * classic_frame_bits(5)) + nodes * HEARTBEAT_HZ * classic_frame_bits(8))
    return per_second / BITRATE


def fd_load(nodes: int, rate_hz: float, sync_hz: float, data_bitrate: float) -> float:
    """The same on CAN FD with one 24-byte frame per sample (the FD variant's budget: it is not
    in the CAN database yet), the Sync, SyncReport and heartbeat as on the classic bus."""
    us = (nodes * rate_hz * fd_frame_us(24, data_bitrate) + sync_hz * (fd_frame_us(1, data_bitrate)
          + nodes * fd_frame_us(5, data_bitrate)) + nodes * HEARTBEAT_HZ * fd_frame_us(8, data_bitrate))
    return us / 1e6


def max_nodes(rate_hz: float, sync_hz: float, load=classic_load) -> int:
    n = 0
    while n < 63 and load(n + 1, rate_hz, sync_hz) <= MAX_LOAD:
        n += 1
    return n


def check(nodes: int, rate_hz: float, sync_hz: float) -> str | None:
    """Why a configuration loads a classic bus too much, or None."""
    load = classic_load(nodes, rate_hz, sync_hz)
    if load <= MAX_LOAD:
        return None
    return (f"{nodes} nodes at {rate_hz:g} Hz with {sync_hz:g} Syncs/s load the CAN bus {100 * load:.0f}% "
            f"(limit {100 * MAX_LOAD:.0f}%: at most {max_nodes(rate_hz, sync_hz)} nodes at this rate; "
            f"docs/imu_bus.md)")


def tables() -> str:
    lines = ["| frame | data bytes | bits, worst case | µs at 1 Mbit/s |", "|---|---|---|---|"]
    for name, n in (("Sync", 1), ("SyncReport", 5), ("ImuQuat, ImuAccel, Heartbeat, Command(Reply)", 8)):
        lines.append(f"| {name} | {n} | {classic_frame_bits(n)} | {classic_frame_bits(n)} |")
    lines += ["", "| nodes | rate (Hz) | classic, 100 Syncs/s | classic, 50 Syncs/s | FD 2 Mbit/s | FD 5 Mbit/s |",
              "|---|---|---|---|---|---|"]
    for nodes, rate in ((6, 60), (13, 60), (13, 120), (17, 60), (17, 120), (13, 240), (17, 400)):
        cells = [classic_load(nodes, rate, 100), classic_load(nodes, rate, 50), fd_load(nodes, rate, 100, 2e6),
                 fd_load(nodes, rate, 100, 5e6)]
        lines.append(f"| {nodes} | {rate} | " + " | ".join(f"{100 * c:.0f}%" for c in cells) + " |")
    lines += ["", f"| rate (Hz) | most nodes under {100 * MAX_LOAD:.0f}%: classic, 100 Syncs/s | classic, 50 | "
              "FD 2 Mbit/s | FD 5 Mbit/s |", "|---|---|---|---|---|"]
    for rate in (60, 100, 120, 200, 240, 400):
        fd2 = max_nodes(rate, 100, lambda n, r, s: fd_load(n, r, s, 2e6))
        fd5 = max_nodes(rate, 100, lambda n, r, s: fd_load(n, r, s, 5e6))
        lines.append(f"| {rate} | {max_nodes(rate, 100)} | {max_nodes(rate, 50)} | {fd2} | {fd5} |")
    return "\n".join(lines)


if __name__ == "__main__":
    print(tables())
