"""The camera box: frames from a source (camera, video, images), optionally paired with
the studio's trigger edges, keypoints from the on-device detector with region tracking,
one KeypointFrame per captured frame published over ZeroMQ.

High-speed mode: detection on `burst` consecutive frames of every `period`; the other
frames are published with detected = false, so the host keeps the frame clock.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterable, Iterator

import zmq

from mocap import transport, wire
from mocap_edge import pacing
from mocap_edge.detect.blazepose import BlazePose, Person
from mocap_edge.detect.tracking import Tracker
from mocap_edge.sources.base import Frame
from mocap_edge.trigger import TriggerPairing


@dataclasses.dataclass
class BoxCounts:
    frames: int = 0
    detected: int = 0
    people: int = 0


def keypoint_frame(camera: str, frame: Frame, people: list[Person] | None, layout: str,
                   send_time_ns: int = 0) -> wire.KeypointFrame:
    """The wire message of a frame; people None: no detection was run on it."""
    h, w = frame.image.shape[:2]
    msg = wire.KeypointFrame(camera_id=camera, frame_index=frame.index, capture_time_ns=frame.capture_time_ns,
                             image_width=w, image_height=h, keypoint_layout=layout, detected=people is not None,
                             send_time_ns=send_time_ns)
    for p in people or []:
        msg.persons.add(x=p.keypoints[:, 0].tolist(), y=p.keypoints[:, 1].tolist(),
                        confidence=p.keypoints[:, 2].tolist(), score=p.presence)
    return msg


def detections(frames: Iterable[Frame], tracker: Tracker, camera: str,
               detect_every: tuple[int, int] = (1, 1)) -> Iterator[tuple[Frame, list[Person] | None]]:
    period, burst = detect_every
    for frame in frames:
        people = tracker.step({camera: frame.image})[camera] if frame.index % period < burst else None
        yield frame, people


def run(frames: Iterable[Frame], camera: str, endpoint: str, detect_every: tuple[int, int] = (1, 1),
        pairing: TriggerPairing | None = None, realtime: bool = False, model=None,
        max_people: int = 2, exposure_mid_ns: int = 0) -> BoxCounts:
    """Publishes every frame of `frames` (paired with trigger edges when given). realtime:
    a file source is played at its capture times instead of as fast as detection runs.
    model: BlazePose (default) or a TopDownModel. exposure_mid_ns: from the trigger edge
    (which a paired frame's time is) to the middle of the exposure, the time KeypointFrame
    names — the sensor's trigger delay plus half the exposure."""
    tracker = Tracker(model or BlazePose(), max_people=max_people)
    socket = transport.publisher(zmq.Context.instance(), endpoint)
    counts = BoxCounts()
    source = frames
    if pairing:
        source = (dataclasses.replace(f, capture_time_ns=f.capture_time_ns + exposure_mid_ns)
                  for f in pairing.pair(frames))
    try:
        for frame, people in detections(source, tracker, camera, detect_every):
            if realtime:
                pacing.sleep_until(frame.capture_time_ns)
            msg = keypoint_frame(camera, frame, people, tracker.model.layout.name, send_time_ns=time.time_ns())
            socket.send_multipart(wire.encode(msg))
            counts.frames += 1
            counts.detected += people is not None
            counts.people += len(people or [])
    finally:
        socket.close(linger=1000)
    return counts
