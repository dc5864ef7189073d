"""ZeroMQ PUB/SUB as the system uses it (edge boxes, IMU hub, host, recorder).

Publishers bind, subscribers connect to every endpoint of the rig configuration and
reconnect by themselves when a box comes back. Bounded queues: a PUB socket whose
subscriber is slow drops at its high-water mark instead of blocking the producer or
growing without bound; a SUB socket likewise drops what it cannot hold.
"""

from __future__ import annotations

import zmq

PUBLISHER_HWM = 2000  # messages: ~3 s of a camera at 60 fps plus slack
SUBSCRIBER_HWM = 20000  # messages: ~3 s of 8 cameras + an IMU hub
RECONNECT_MS = (100, 250)  # first retry, back-off ceiling (as mocapd's: a box back is found within 250 ms)


def publisher(context: zmq.Context, endpoint: str, hwm: int = PUBLISHER_HWM) -> zmq.Socket:
    socket = context.socket(zmq.PUB)
    socket.setsockopt(zmq.SNDHWM, hwm)
    socket.setsockopt(zmq.LINGER, 500)
    socket.bind(endpoint)
    return socket


def subscriber(context: zmq.Context, endpoints: list[str], hwm: int = SUBSCRIBER_HWM) -> zmq.Socket:
    socket = context.socket(zmq.SUB)
    socket.setsockopt(zmq.RCVHWM, hwm)
    socket.setsockopt(zmq.RECONNECT_IVL, RECONNECT_MS[0])
    socket.setsockopt(zmq.RECONNECT_IVL_MAX, RECONNECT_MS[1])
    socket.setsockopt(zmq.LINGER, 0)
    socket.setsockopt(zmq.SUBSCRIBE, b"")
    for endpoint in endpoints:
        socket.connect(endpoint)
    return socket
