"""The hub's CAN adapter: a python-can bus from a URI.

    socketcan:can0                a CAN interface of the box (SocketCAN)
    slcan:socket://HOST:PORT      an SLCAN (LAWICEL) adapter over TCP: the firmware running in QEMU
    slcan:/dev/ttyACM0            a USB-CAN adapter speaking SLCAN
    socketcand:HOST:PORT:CHANNEL  a CAN interface of another machine served by socketcand (the
                                  simulated studio's nodes: mocap_edge.hub.sim.socketcand)
    virtual:NAME                  python-can's in-process bus (tests)

The hub needs each Sync's transmit time. SocketCAN and the virtual bus echo the hub's own
frames (receive_own_messages) with their timestamp: that echo is the transmit time. An SLCAN
adapter and socketcand do not echo: the time just before `send` is used — the frame leaves
later by the adapter's (or the network's) queuing, a delay the clock fit's upper envelope
tolerates, never earlier.
"""

from __future__ import annotations

import dataclasses
import logging
import socket

import can

from mocap_edge.errors import EdgeError

ECHOING = ("socketcan", "virtual")


@dataclasses.dataclass
class CanPort:
    bus: can.BusABC
    echoes: bool  # the bus hands back the frames it sent, stamped when they left
    name: str = "the CAN bus"  # in messages: the URI it was opened from


def open_bus(uri: str, own_messages: bool = True) -> CanPort:
    """The bus a URI names; EdgeError when it cannot be opened. own_messages=False: the frames
    this port sends are not handed back (simulated nodes, which need no transmit times)."""
    interface, _, channel = uri.partition(":")
    if interface not in ("socketcan", "slcan", "socketcand", "virtual") or not channel:
        raise EdgeError(f"--can {uri!r}: socketcan:IFACE, slcan:socket://HOST:PORT, slcan:DEVICE, "
                        "socketcand:HOST:PORT:CHANNEL or virtual:NAME")
    if interface == "socketcand":
        options = _socketcand_options(uri, channel)
        # python-can warns at every read that ends inside a message (most reads, at speed)
        logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)
    else:
        options = {"receive_own_messages": own_messages} if interface in ECHOING else {"bitrate": 1_000_000}
    try:
        bus = can.Bus(interface=interface, **{"channel": channel, **options})
        return CanPort(bus, own_messages and interface in ECHOING, f"--can {uri}")
    except (can.CanError, OSError, ValueError, TimeoutError) as e:
        raise EdgeError(f"--can {uri}: {e}") from None


def _socketcand_options(uri: str, address: str) -> dict:
    host, _, rest = address.partition(":")
    port, _, channel = rest.partition(":")
    if not (host and port.isdigit() and channel):
        raise EdgeError(f"--can {uri!r}: socketcand:HOST:PORT:CHANNEL, e.g. socketcand:10.0.0.5:29536:can0")
    try:  # python-can retries a refused connection for 10 s in a busy loop: look first
        socket.create_connection((host, int(port)), timeout=1.0).close()
    except OSError as e:
        raise EdgeError(f"--can {uri}: {e}") from None
    return {"host": host, "port": int(port), "channel": channel, "tcp_tune": True}
