"""The hub's CAN adapter: a python-can bus from a URI.

    socketcan:can0                a CAN interface of the box (SocketCAN)
    slcan:socket://HOST:PORT      an SLCAN (LAWICEL) adapter over TCP: the firmware running in QEMU
    slcan:/dev/ttyACM0            a USB-CAN adapter speaking SLCAN
    virtual:NAME                  python-can's in-process bus (tests, the simulated studio)

The hub needs each Sync's transmit time. SocketCAN and the virtual bus echo the hub's own
frames (receive_own_messages) with their timestamp: that echo is the transmit time. An SLCAN
adapter does not echo: the time `send` returned is used, later than the frame left by the
adapter's queuing, which the clock fit's upper envelope tolerates.
"""

from __future__ import annotations

import dataclasses

import can

from mocap_edge.errors import EdgeError

ECHOING = ("socketcan", "virtual")


@dataclasses.dataclass
class CanPort:
    bus: can.BusABC
    echoes: bool  # the bus hands back the frames it sent, stamped when they left


def open_bus(uri: str, own_messages: bool = True) -> CanPort:
    """The bus a URI names; EdgeError when it cannot be opened. own_messages=False: the frames
    this port sends are not handed back (simulated nodes, which need no transmit times)."""
    interface, _, channel = uri.partition(":")
    if interface not in ("socketcan", "slcan", "virtual") or not channel:
        raise EdgeError(f"--can {uri!r}: socketcan:IFACE, slcan:socket://HOST:PORT, slcan:DEVICE or virtual:NAME")
    options = {"receive_own_messages": own_messages} if interface in ECHOING else {"bitrate": 1_000_000}
    try:
        return CanPort(can.Bus(interface=interface, channel=channel, **options), own_messages and interface in ECHOING)
    except (can.CanError, OSError, ValueError) as e:
        raise EdgeError(f"--can {uri}: {e}") from None
