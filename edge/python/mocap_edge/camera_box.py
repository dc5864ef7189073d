"""The camera box: frames from a source (camera, video, images, the simulated studio),
optionally paired with the studio's trigger edges, keypoints from a model (detect/) with
region tracking, one KeypointFrame per captured frame published over ZeroMQ.

High-speed mode: detection on `burst` consecutive frames of every `period`; the other
frames are published with detected = false, so the host keeps the frame clock.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Iterable, Iterator

import zmq

from mocap.net import transport, wire
from mocap.net.keys import ServerKeys
from mocap_edge import pacing
from mocap_edge.errors import EdgeError
from mocap_edge.detect.base import Detector, Person, open_detector
from mocap_edge.detect.tracking import Tracker
from mocap_edge.sources.base import Frame
from mocap_edge.trigger import TriggerPairing

log = logging.getLogger(__name__)
BIND_ATTEMPTS, BIND_RETRY_S = 50, 0.02  # a box started again on its endpoint waits for the port


@dataclasses.dataclass
class BoxCounts:
    frames: int = 0
    detected: int = 0
    people: int = 0

    def add(self, people: list[Person] | None) -> None:
        self.frames += 1
        self.detected += people is not None
        self.people += len(people or [])

    def __add__(self, other: BoxCounts) -> BoxCounts:
        return BoxCounts(self.frames + other.frames, self.detected + other.detected, self.people + other.people)


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


def bind(endpoint: str, keys: ServerKeys | None = None) -> zmq.Socket:
    """The box's publisher (a CURVE server with keys); the port of a box that ran before in
    this process is released by ZeroMQ shortly after its socket closed, so binding is retried
    for a second."""
    context = zmq.Context.instance()
    for _ in range(BIND_ATTEMPTS - 1):
        try:
            return transport.publisher(context, endpoint, keys=keys)
        except zmq.ZMQError as e:
            log.debug("cannot bind %s yet (%s): retrying", endpoint, e)
            time.sleep(BIND_RETRY_S)
    return transport.publisher(context, endpoint, keys=keys)


def paired(frames: Iterable[Frame], pairing: TriggerPairing | None, exposure_mid_ns: int) -> Iterable[Frame]:
    """The frames with their trigger edge's time (moved to mid-exposure) and count, if paired."""
    if pairing is None:
        return frames
    return (dataclasses.replace(f, capture_time_ns=f.capture_time_ns + exposure_mid_ns) for f in pairing.pair(frames))


MAX_PEOPLE = 4  # tracked per frame
REDETECT_EVERY = 15  # frames (4 Hz at 60 fps): the person detector looks for newcomers


def run(frames: Iterable[Frame], camera: str, endpoint: str, detect_every: tuple[int, int] = (1, 1),
        pairing: TriggerPairing | None = None, realtime: bool = False, model: Detector | None = None,
        max_people: int = MAX_PEOPLE, exposure_mid_ns: int = 0, keys: ServerKeys | None = None,
        redetect_every: int = REDETECT_EVERY) -> BoxCounts:
    """Publishes every frame of `frames` (paired with trigger edges when given). realtime:
    a file source is played at its capture times instead of as fast as detection runs.
    model: any Detector (default BlazePose). exposure_mid_ns: from the trigger edge (which
    a paired frame's time is) to the middle of the exposure, the time KeypointFrame names —
    the sensor's trigger delay plus half the exposure. keys: the box's CURVE identity (None:
    a stream without keys). redetect_every: frames between the person detector's looks for
    newcomers while people are tracked (0: only once everyone is lost)."""
    if max_people < 1 or redetect_every < 0:
        raise EdgeError(f"max_people must be >= 1 and redetect_every >= 0, not {max_people} and {redetect_every}")
    tracker = Tracker(model or open_detector("blazepose"), max_people=max_people, redetect_every=redetect_every)
    socket, counts = bind(endpoint, keys), BoxCounts()
    try:
        for frame, people in detections(paired(frames, pairing, exposure_mid_ns), tracker, camera, detect_every):
            if realtime:
                pacing.sleep_until(frame.capture_time_ns)
            msg = keypoint_frame(camera, frame, people, tracker.model.layout.name, send_time_ns=time.time_ns())
            socket.send_multipart(wire.encode(msg))
            counts.add(people)
    finally:
        socket.close(linger=1000)
    return counts
