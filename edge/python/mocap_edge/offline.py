"""The messages the edge boxes send for a stream file (mocap_edge.streams), made at once
instead of in real time: each camera's through the camera box's own pieces (the `sim:`
frame source and keypoint model, the tracker, `camera_box.keypoint_frame`), the IMUs' as
simulated sensor nodes through the hub's decoding, clock fit and batching on a simulated CAN
bus (`hub.sim.studio.studio_batches`). Each comes with the time it reaches the host: a
camera frame when the simulated detection finishes (capture + latency and jitter, as the
live box sends it), a batch when the hub sends it. A host fed these in arrival order sees
what it would see live, without the machine's scheduling.
"""

from __future__ import annotations

from pathlib import Path

from mocap.net import wire

from mocap_edge import camera_box
from mocap_edge.detect.sim import SimulatedDetector
from mocap_edge.detect.tracking import Tracker
from mocap_edge.hub.sim.studio import studio_batches
from mocap_edge.sources.sim import SimulatedSource
from mocap_edge.streams import Streams


def camera_messages(streams: Path, camera: str, start_ns: int, detect_every: tuple[int, int] = (1, 1),
                    seed: int = 0) -> list[tuple[int, wire.KeypointFrame]]:
    """(arrival ns, message) of the camera box playing `camera` of the stream file from
    start_ns (a time already past: nothing waits)."""
    source = SimulatedSource(str(streams), camera, start_ns=start_ns)
    model = SimulatedDetector(str(streams), camera, start_ns=start_ns, seed=seed)
    out = []
    for frame, people in camera_box.detections(source, Tracker(model), camera, detect_every):
        arrival = int(model.ready_ns[frame.index])
        out.append((arrival, camera_box.keypoint_frame(camera, frame, people, model.layout.name, arrival)))
    return out


def studio_messages(streams: Path, start_ns: int, detect_every: tuple[int, int] = (1, 1)) -> list[tuple[int, object]]:
    """(arrival ns, message) of every camera box and the IMU hub, in arrival order (cameras
    before the hub at the same time; each box's detector jitter seeded by its index)."""
    studio = Streams.load(Path(streams))
    out = [m for i, c in enumerate(studio.camera_ids) for m in camera_messages(streams, c, start_ns, detect_every, i)]
    out += [(b.send_time_ns, b) for b in studio_batches(studio, start_ns)]
    out.sort(key=lambda m: (m[0], isinstance(m[1], wire.ImuBatch)))
    return out
