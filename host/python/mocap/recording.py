"""Recording the streams to MCAP files, and replaying them on ZeroMQ.

A recording has one channel per stream, its topic taken from the message:

| message | topic | publish_time (the message's own time) |
|---|---|---|
| KeypointFrame | /camera/<camera_id> | capture_time_ns |
| ImuBatch | /imu/<hub_id> | send_time_ns |
| PoseFrame | /pose | capture_time_ns |
| Health | /health/<source> | time_ns |

log_time is the arrival time at the recorder (time.time_ns()). Messages are stored as the
received bytes (message encoding "protobuf"), so fields unknown to this version survive.
Each message type has one schema: encoding "protobuf", name = full type name, data = a
serialised FileDescriptorSet of the type's .proto file and all its dependencies. A
recording is thus self-describing (Foxglove opens it as is; `read` needs no generated code).
"""

from __future__ import annotations

import fnmatch
import json
import logging
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

import zmq
from google.protobuf import descriptor_pb2
from google.protobuf.message import Message
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.writer import Writer

from mocap import transport, wire
from mocap.errors import InputError

log = logging.getLogger(__name__)

INPUT_TOPICS = ("/camera/*", "/imu/*", "/calibration/*")  # what `replay` sends by default: the host's inputs
POLL_MS = 100  # how often `record` checks its stop conditions
BACKPRESSURE_SLEEP_S = 0.001  # `replay`'s pause while a subscriber's queue is full
REPLAY_LINGER_MS = 10_000  # time the last queued messages get to reach slow subscribers


@dataclass(frozen=True)
class RecordedMessage:
    log_time_ns: int
    topic: str
    type_name: str  # "mocap.v1.KeypointFrame", the ZeroMQ type frame
    payload: bytes


@dataclass(frozen=True)
class Counts:
    recorded: dict[str, int]  # per topic
    dropped: dict[str, int]  # per wire.WireError reason


def topic_and_time(message) -> tuple[str, int]:
    """The MCAP topic of a decoded message, and its own time (ns; see the module docstring)."""
    match message:
        case wire.KeypointFrame():
            return f"/camera/{message.camera_id}", message.capture_time_ns
        case wire.ImuBatch():
            return f"/imu/{message.hub_id}", message.send_time_ns
        case wire.PoseFrame():
            return "/pose", message.capture_time_ns
        case wire.Health():
            return f"/health/{message.source}", message.time_ns
        case wire.Calibration():
            return f"/calibration/{message.source}", message.valid_from_ns
    raise TypeError(f"no topic for {type(message).__name__}")


def file_descriptor_set(message_descriptor) -> bytes:
    """The serialised FileDescriptorSet of a message type's file and its dependencies, dependencies first."""
    files = descriptor_pb2.FileDescriptorSet()
    seen: set[str] = set()

    def add(file) -> None:
        if file.name in seen:
            return
        seen.add(file.name)
        for dependency in file.dependencies:
            add(dependency)
        file.CopyToProto(files.file.add())

    add(message_descriptor.file)
    return files.SerializeToString()


SESSION_FILES = ("skeleton", "rig", "layout", "imus", "prior")


class Recorder:
    """Writes well-formed mocap.v1 messages to an MCAP file; counts and skips the others."""

    def __init__(self, path: str | Path, on_record: Callable[[str, Message], None] | None = None):
        """on_record, if given, is called with the topic and the decoded message of every
        recorded message (progress, a calibration's watch on the motion, tests)."""
        self._on_record = on_record
        self._writer = Writer(str(path))
        self._writer.start(profile="protobuf", library="mocap recording")
        self._schema_ids: dict[str, int] = {}
        self._channel_ids: dict[str, int] = {}
        self._closed = False
        self.recorded: Counter[str] = Counter()
        self.dropped: Counter[str] = Counter()

    def write(self, frames: list[bytes], log_time_ns: int) -> bool:
        """Records a two-frame [type, payload] message received at log_time_ns; False if it was dropped."""
        try:
            message = wire.decode(frames)
        except wire.WireError as e:
            self.dropped[e.reason] += 1
            log.debug("dropped: %s", e)
            return False
        topic, own_time_ns = topic_and_time(message)
        self._writer.add_message(self._channel_id(topic, message.DESCRIPTOR), log_time=log_time_ns,
                                 data=bytes(frames[1]), publish_time=max(own_time_ns, 0))  # MCAP times are unsigned
        self.recorded[topic] += 1
        if self._on_record is not None:
            self._on_record(topic, message)
        return True

    def attach_session(self, session: str | Path) -> None:
        """Attaches the session file and the files it names (skeleton, rig, layout, IMU set,
        prior), so that the recording can be solved without them (read_session)."""
        session = Path(session)
        config = json.loads(session.read_text())
        for key in SESSION_FILES:
            if config.get(key):
                source = session.parent / config[key]
                config[key] = f"{key}.json"
                self._attach(f"session/{key}.json", source.read_bytes())
        self._attach("session/session.json", json.dumps(config, indent=1).encode())

    def _attach(self, name: str, data: bytes) -> None:
        now = time.time_ns()
        self._writer.add_attachment(create_time=now, log_time=now, name=name, media_type="application/json", data=data)

    def counts(self) -> Counts:
        return Counts(dict(self.recorded), dict(self.dropped))

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._writer.finish()  # writes the index and closes the file

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _channel_id(self, topic: str, descriptor) -> int:
        if topic not in self._channel_ids:
            name = descriptor.full_name
            if name not in self._schema_ids:
                self._schema_ids[name] = self._writer.register_schema(name, "protobuf", file_descriptor_set(descriptor))
            self._channel_ids[topic] = self._writer.register_channel(topic, "protobuf", self._schema_ids[name])
        return self._channel_ids[topic]


def record(endpoints: list[str], path: str | Path, seconds: float | None = None,
           stop: threading.Event | None = None, on_record: Callable[[str, Message], None] | None = None,
           session: str | Path | None = None) -> Counts:
    """Records what the publishers at `endpoints` send until `seconds` have passed or `stop` is
    set; with the session's files attached when given."""
    deadline = None if seconds is None else time.monotonic() + seconds
    stop = stop or threading.Event()
    with Recorder(path, on_record) as recorder, zmq.Context() as context, transport.subscriber(context, endpoints) as socket:
        if session is not None:
            recorder.attach_session(session)
        while not stop.is_set() and (deadline is None or time.monotonic() < deadline):
            if socket.poll(POLL_MS):
                recorder.write(socket.recv_multipart(), time.time_ns())
        return recorder.counts()


def read(path: str | Path) -> Iterator[RecordedMessage]:
    """The messages of a recording in log-time order."""
    with open(path, "rb") as stream:
        yield from _messages(stream, str(path))


def read_session(path: str | Path, folder: str | Path) -> Path | None:
    """Extracts the session attached to a recording into `folder`; its session file, or
    None when the recording has none."""
    found = None
    with open(path, "rb") as stream:
        try:
            attachments = list(make_reader(stream).iter_attachments())
        except McapError as e:
            raise InputError(f"{path}: not an MCAP file ({e})") from None
    for a in attachments:
        if a.name.startswith("session/"):
            target = Path(folder) / Path(a.name).name
            target.write_bytes(a.data)
            found = target if target.name == "session.json" else found
    return found


def _messages(stream: BinaryIO, name: str) -> Iterator[RecordedMessage]:
    try:
        reader = make_reader(stream)  # checks the magic now, not at the first message
    except McapError as e:
        raise InputError(f"{name}: not an MCAP file ({e})") from None
    return (RecordedMessage(message.log_time, channel.topic, schema.name if schema else "", message.data)
            for schema, channel, message in reader.iter_messages(log_time_order=True))


def replay(path: str | Path, endpoint: str, speed: float | None = 1.0, topics: Iterable[str] | None = None,
           wait_for_subscribers: float = 1.0, restamp: bool = False) -> int:
    """Publishes the recorded messages on `endpoint` as [type, payload]; returns how many were sent.

    topics: fnmatch patterns of the topics to send (default INPUT_TOPICS, the host's inputs).
    speed: times real time, following the log-time gaps; None sends as fast as the subscribers take
    them. Pacing never blocks inside ZeroMQ: the socket refuses a message at a subscriber's
    high-water mark (XPUB_NODROP) and the replay sleeps BACKPRESSURE_SLEEP_S and retries, so a slow
    subscriber slows the replay down instead of losing messages.
    Sending starts when a first subscriber has joined, or after wait_for_subscribers seconds.
    restamp (with a speed): every capture, sample and send time is moved by the time between
    the recording and now, so a live host takes the replay for a take happening now (its
    synchroniser waits for inputs by their capture time); the recording's own bytes otherwise.
    """
    if restamp and speed is None:
        raise InputError("restamping needs a replay speed: as fast as possible has no 'now'")
    if speed is not None and not speed > 0:
        raise InputError(f"replay speed must be positive, not {speed}")
    patterns = tuple(INPUT_TOPICS if topics is None else topics)
    with open(path, "rb") as stream:
        messages = (m for m in _messages(stream, str(path)) if any(fnmatch.fnmatchcase(m.topic, p) for p in patterns))
        with zmq.Context() as context, _replay_socket(context, endpoint) as socket:
            if socket.poll(wait_for_subscribers * 1000):
                socket.recv()  # the first subscription
            return _publish(socket, messages, speed, restamp)


def _publish(socket: zmq.Socket, messages: Iterable[RecordedMessage], speed: float | None,
             restamp: bool = False) -> int:
    sent, start_s, start_ns, first_log_ns = 0, time.monotonic(), time.time_ns(), None
    for m in messages:
        payload = m.payload
        if speed is not None:
            first_log_ns = m.log_time_ns if first_log_ns is None else first_log_ns
            time.sleep(max(0.0, start_s + (m.log_time_ns - first_log_ns) / 1e9 / speed - time.monotonic()))
            if restamp:
                payload = _shifted(m, start_ns - first_log_ns)
        _send(socket, [m.type_name.encode(), payload])
        sent += 1
    return sent


def _shifted(m: RecordedMessage, offset_ns: int) -> bytes:
    """The message with its times moved by offset_ns (inputs only; others unchanged)."""
    message = wire.TYPES[m.type_name].FromString(m.payload)
    if isinstance(message, wire.KeypointFrame):
        message.capture_time_ns += offset_ns
        message.send_time_ns += offset_ns if message.send_time_ns else 0
    elif isinstance(message, wire.ImuBatch):
        message.send_time_ns += offset_ns if message.send_time_ns else 0
        for sample in message.samples:
            sample.sample_time_ns += offset_ns
    elif isinstance(message, wire.Calibration):  # from the same moment of the take
        message.valid_from_ns += offset_ns
    return message.SerializeToString()  # closing the socket then waits (LINGER) for the queued messages to leave


def _replay_socket(context: zmq.Context, endpoint: str) -> zmq.Socket:
    """A PUB socket that reports subscriptions and refuses (instead of dropping) at the high-water mark."""
    socket = context.socket(zmq.XPUB)
    socket.setsockopt(zmq.SNDHWM, transport.PUBLISHER_HWM)
    socket.setsockopt(zmq.XPUB_NODROP, 1)
    socket.setsockopt(zmq.LINGER, REPLAY_LINGER_MS)
    socket.bind(endpoint)
    return socket


def _send(socket: zmq.Socket, frames: list[bytes]) -> None:
    while True:
        try:
            socket.send_multipart(frames, zmq.NOBLOCK)
            return
        except zmq.Again:
            time.sleep(BACKPRESSURE_SLEEP_S)
