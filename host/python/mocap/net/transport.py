"""ZeroMQ PUB/SUB as the system uses it (edge boxes, IMU hub, host, recorder).

Publishers bind, subscribers connect to every endpoint of the rig configuration and
reconnect by themselves when a box comes back. Bounded queues: a PUB socket whose
subscriber is slow drops at its high-water mark instead of blocking the producer or
growing without bound; a SUB socket likewise drops what it cannot hold.

With CURVE keys (`mocap.net.keys`) a publisher is a CURVE server holding its key pair, and
a subscriber a CURVE client that expects each endpoint's server key: the streams are then
authenticated and encrypted. A server given the clients it admits checks each client's key
in a ZAP handler, and counts the refused ones (`refused`). ZeroMQ has one ZAP handler per
context: it admits the keys of every publisher of that context (a box has one publisher), and
once started it checks the clients of every CURVE publisher of the context.
"""

from __future__ import annotations

import zmq
from zmq.auth.thread import ThreadAuthenticator

from mocap.net.keys import ClientKeys, ServerKeys

PUBLISHER_HWM = 2000  # messages: ~3 s of a camera at 60 fps plus slack
SUBSCRIBER_HWM = 20000  # messages: ~3 s of 8 cameras + an IMU hub
RECONNECT_MS = (100, 250)  # first retry, back-off ceiling (as mocapd's: a box back is found within 250 ms)
# A subscriber pings each publisher every second and drops a connection unanswered for 3 s (as
# mocapd's): a hung box or a pulled cable leaves its TCP connection open, and a SUB that sends
# nothing would hold it for good, never connecting to the box once it is back.
HEARTBEAT_MS = (1000, 3000)  # ping interval, timeout


class _Allowed:
    """The ZAP handler's check: a client key in the allowed set; counts the others."""

    def __init__(self) -> None:
        self.keys: set[bytes] = set()
        self.refused = 0

    def callback(self, domain: str, key: bytes) -> bool:
        if key in self.keys:
            return True
        self.refused += 1
        return False


_ALLOWED: dict[int, tuple[ThreadAuthenticator, _Allowed]] = {}  # per context


def _admit(context: zmq.Context, allowed: frozenset[str]) -> None:
    """Starts the context's ZAP handler once; admits these client keys (too)."""
    if id(context) not in _ALLOWED:
        auth = ThreadAuthenticator(context)
        auth.start()
        check = _Allowed()
        auth.configure_curve_callback("*", credentials_provider=check)
        _ALLOWED[id(context)] = (auth, check)
    _ALLOWED[id(context)][1].keys.update(k.encode() for k in allowed)


def refused(context: zmq.Context) -> int:
    """Clients the context's ZAP handler refused (0 without one)."""
    entry = _ALLOWED.get(id(context))
    return entry[1].refused if entry else 0


def publisher(context: zmq.Context, endpoint: str, hwm: int = PUBLISHER_HWM,
              keys: ServerKeys | None = None) -> zmq.Socket:
    socket = context.socket(zmq.PUB)
    socket.setsockopt(zmq.SNDHWM, hwm)
    socket.setsockopt(zmq.LINGER, 500)
    if keys is not None:
        if keys.allowed is not None:
            _admit(context, keys.allowed)
        socket.curve_server = True
        socket.curve_secretkey = keys.pair.secret.encode()
    socket.bind(endpoint)
    return socket


def subscriber(context: zmq.Context, endpoints: list[str], hwm: int = SUBSCRIBER_HWM,
               keys: ClientKeys | None = None) -> zmq.Socket:
    socket = context.socket(zmq.SUB)
    socket.setsockopt(zmq.RCVHWM, hwm)
    socket.setsockopt(zmq.RECONNECT_IVL, RECONNECT_MS[0])
    socket.setsockopt(zmq.RECONNECT_IVL_MAX, RECONNECT_MS[1])
    socket.setsockopt(zmq.HEARTBEAT_IVL, HEARTBEAT_MS[0])
    socket.setsockopt(zmq.HEARTBEAT_TIMEOUT, HEARTBEAT_MS[1])
    socket.setsockopt(zmq.LINGER, 0)
    socket.setsockopt(zmq.SUBSCRIBE, b"")
    if keys is not None:
        socket.curve_publickey = keys.pair.public.encode()
        socket.curve_secretkey = keys.pair.secret.encode()
    for endpoint in endpoints:
        if keys is not None:  # each connection takes the server key set before it
            socket.curve_serverkey = keys.server(endpoint).encode()
        socket.connect(endpoint)
    return socket
