"""The camera node: one KeypointFrame per captured frame, published when the box would
have it (capture + detection time + jitter).

Sources today: a stream file (the simulated studio). Live capture and on-device detection
are the camera box issue's."""

from __future__ import annotations

import time

import numpy as np
import zmq

from mocap import transport, wire
from mocap_edge import pacing
from mocap_edge.streams import Streams


def keypoint_frame(streams: Streams, f: int, c: int, start_ns: int) -> wire.KeypointFrame:
    w, h = (int(v) for v in streams.image_sizes[c])
    msg = wire.KeypointFrame(camera_id=streams.camera_ids[c], frame_index=f,
                             capture_time_ns=start_ns + int(streams.frame_times_ns[f]), image_width=w,
                             image_height=h, keypoint_layout=streams.layout, detected=bool(streams.detected[f]))
    if streams.detected[f]:
        k = streams.keypoints[f, c]
        if (k[:, 2] > 0).any():
            msg.persons.add(x=k[:, 0].tolist(), y=k[:, 1].tolist(), confidence=k[:, 2].tolist())
    return msg


def _rebind(context: zmq.Context, endpoint: str, attempts: int = 50) -> zmq.Socket:
    """A new publisher on the endpoint a closed one held (ZeroMQ releases it shortly after)."""
    for _ in range(attempts - 1):
        try:
            return transport.publisher(context, endpoint)
        except zmq.ZMQError:
            time.sleep(0.02)
    return transport.publisher(context, endpoint)


def run(streams: Streams, camera: str, endpoint: str, start_ns: int, detect_ms: float = 6.0,
        jitter_ms: float = 0.5, seed: int = 0, stop_at: tuple[float, float] | None = None) -> int:
    """Plays one camera of the streams in real time from start_ns; returns frames sent.
    stop_at (from_s, to_s) unplugs the box (closes its socket) for that span of the take."""
    c = streams.camera_ids.index(camera)
    rng = np.random.default_rng(seed)
    context = zmq.Context.instance()
    socket = transport.publisher(context, endpoint)
    sent = 0
    try:
        for f in range(len(streams.frame_times_ns)):
            t = streams.frame_times_ns[f] * 1e-9
            if stop_at and stop_at[0] <= t < stop_at[1]:  # unplugged: the socket is gone
                if not socket.closed:
                    socket.close(linger=0)
                continue
            if socket.closed:  # plugged back in: the host's subscriber reconnects by itself
                socket = _rebind(context, endpoint)
            msg = keypoint_frame(streams, f, c, start_ns)
            ready = msg.capture_time_ns + int(1e6 * (detect_ms + rng.exponential(jitter_ms)))
            pacing.sleep_until(ready)
            msg.send_time_ns = ready
            socket.send_multipart(wire.encode(msg))
            sent += 1
    finally:
        socket.close(linger=500)
    return sent
