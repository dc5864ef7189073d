"""Recording the streams to MCAP files (reading them back: mocap.recording.reader).

A recording has one channel per stream, its topic taken from the message:

| message | topic | publish_time (the message's own time) |
|---|---|---|
| KeypointFrame | /camera/<camera_id> | capture_time_ns |
| ImuBatch | /imu/<hub_id> | send_time_ns |
| PoseFrame | /pose | capture_time_ns |
| Health | /health/<source> | time_ns |
| Calibration | /calibration/<source> | valid_from_ns |

Beside each PoseFrame, the skeleton in Foxglove's schemas on /skeleton/transforms and
/skeleton/scene (mocap.recording.foxglove; its bones from the attached session's skeleton,
else the default skeleton's where the names match), so that Foxglove shows the performer.

log_time is the arrival time at the recorder (time.time_ns()). Messages are stored as the
received bytes (message encoding "protobuf"), so fields unknown to this version survive.
Each message type has one schema: encoding "protobuf", name = full type name, data = a
serialised FileDescriptorSet of the type's .proto file and all its dependencies. A
recording is thus self-describing (Foxglove opens it as is; reading needs no generated code).
A session attached (`attach_session`) travels as attachments session/session.json and the
files it names (mocap.recording.reader.read_session extracts them).

A recorder killed (SIGKILL, a power cut of the process) leaves every chunk it closed: a chunk
is closed and handed to the OS when CHUNK_S has passed since its first message (or at
CHUNK_BYTES), so a kill loses the last CHUNK_S of messages at most, plus what the writer had
not taken from its queue (mocap.recording.recover makes the file indexed again). Shorter
chunks lose less and cost more: each adds its header, message indexes and an index entry,
and compresses worse (docs/reliability.md, "Recordings", measures both).
"""

from __future__ import annotations

import dataclasses
import logging
import queue
import threading
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path

import zmq
from google.protobuf import descriptor_pb2
from google.protobuf.message import Message
from mcap.data_stream import RecordBuilder
from mcap.records import ChunkIndex
from mcap.writer import Writer

from mocap import paths
from mocap.errors import InputError
from mocap.io.session import FILES, Session
from mocap.net import transport, wire
from mocap.net.keys import ClientKeys
from mocap.recording import foxglove

log = logging.getLogger(__name__)

POLL_MS = 100  # how often `record` checks its stop conditions (and closes a chunk that is due)
CHUNK_S = 0.25  # a chunk is closed at most this long after its first message: what a kill can lose
CHUNK_BYTES = 1 << 20  # ... or when it reaches this size (mcap's default)


class PackedChunkIndexes:
    """The writer's chunk index kept as the bytes it will write at the file's end (~180 bytes
    a chunk) instead of a Python record each (~1.5 kB): with a chunk every CHUNK_S, an hour's
    take holds ~2.6 MB of index, not ~14 (docs/reliability.md, "Soak"). mcap's Writer only
    appends to its index and, when it finishes, writes every entry (mcap==1.2.2, pinned)."""

    def __init__(self) -> None:
        self._records = bytearray()
        self.count = 0

    def append(self, index: ChunkIndex) -> None:
        builder = RecordBuilder()
        index.write(builder)
        self._records += builder.end()
        self.count += 1

    def __iter__(self):
        yield self  # one entry that writes them all

    def write(self, builder: RecordBuilder) -> None:
        builder.write(bytes(self._records))


@dataclasses.dataclass(frozen=True)
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


class Recorder:
    """Writes well-formed mocap.v1 messages to an MCAP file; counts and skips the others."""

    def __init__(self, path: str | Path, on_record: Callable[[str, Message], None] | None = None,
                 chunk_s: float = CHUNK_S, clock: Callable[[], float] = time.monotonic):
        """on_record, if given, is called with the topic and the decoded message of every
        recorded message (progress, a calibration's watch on the motion, tests). chunk_s: the
        longest a chunk stays open, by `clock` (s)."""
        self._on_record = on_record
        self._file = open(path, "wb")
        self._writer = Writer(self._file, chunk_size=CHUNK_BYTES)
        self._writer._Writer__chunk_indices = PackedChunkIndexes()
        self._writer.start(profile="protobuf", library="mocap recording")
        self._chunk_s, self._clock, self._chunk_opened = chunk_s, clock, None
        self._parents = foxglove.skeleton_parents(paths.DEFAULT_SKELETON)  # the session's, once attached
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
        if isinstance(message, wire.PoseFrame):
            self._write_skeleton_views(message, log_time_ns)
        self._chunk_opened = self._clock() if self._chunk_opened is None else self._chunk_opened
        self.flush_if_due()
        if self._on_record is not None:
            self._on_record(topic, message)
        return True

    def _write_skeleton_views(self, pose: wire.PoseFrame, log_time_ns: int) -> None:
        """The PoseFrame's skeleton in Foxglove's schemas, at the PoseFrame's times."""
        for topic, view in foxglove.skeleton_messages(pose, self._parents):
            self._writer.add_message(self._channel_id(topic, view.DESCRIPTOR), log_time=log_time_ns,
                                     data=view.SerializeToString(), publish_time=max(pose.capture_time_ns, 0))

    def flush_if_due(self) -> None:
        """Closes the open chunk if it has been open for chunk_s (call it while idle too)."""
        if self._chunk_opened is not None and self._clock() - self._chunk_opened >= self._chunk_s:
            self.flush()

    def flush(self) -> None:
        """Closes the open chunk and hands the file's bytes to the OS: they survive a kill of
        this process (not a power cut: no fsync). mcap's Writer closes a chunk only when it
        outgrows chunk_size and has no public call for it; this is the method its finish()
        uses (mcap==1.2.2, pinned; tests/test_recording.py checks the chunks' times)."""
        self._writer._Writer__finalize_chunk()
        self._file.flush()
        self._chunk_opened = None

    def attach_session(self, session: str | Path) -> None:
        """Attaches the session file and the files it names (skeleton, rig, layout, IMU set,
        prior, the suits' IMU sets and skeletons), so that the recording can be solved without them (reader.read_session). Its
        "curve" keys are left out: they are the live streams', and the host's secret key file
        is never copied into a recording."""
        config = Session.load(session)
        if (skeleton := config.file("skeleton")) is not None:
            self._parents = foxglove.skeleton_parents(skeleton)
        renamed = {}
        for key in FILES:
            source = config.file(key)
            if source is not None:
                self._attach(f"session/{key}.json", source.read_bytes())
                renamed[key] = f"{key}.json"
        suits = []  # several people: each suit's IMU set and skeleton, renamed suitN_KEY.json
        for n, suit in enumerate(config.suits):
            suits.append({key: f"suit{n}_{key}.json" for key in suit})
            for key, name in suit.items():
                self._attach(f"session/suit{n}_{key}.json", (config.base / name).read_bytes())
        attached = dataclasses.replace(config, curve=None, suits=suits, **renamed)
        self._attach("session/session.json", attached.dumps().encode())
        self._file.flush()

    def _attach(self, name: str, data: bytes) -> None:
        now = time.time_ns()
        self._writer.add_attachment(create_time=now, log_time=now, name=name, media_type="application/json", data=data)

    def counts(self) -> Counts:
        return Counts(dict(self.recorded), dict(self.dropped))

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._writer.finish()  # writes the index
            self._file.close()

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
    set; with the session's files attached when given. A thread of its own receives and stamps
    each message as it arrives: writing (decoding, MCAP's chunks and their compression) takes
    tens of milliseconds now and then, and stamps taken after it would be that late — later
    than the host's synchroniser waits, so the recording solved again would drop camera frames
    the live host used."""
    check_endpoints(endpoints)
    deadline = None if seconds is None else time.monotonic() + seconds
    stop = stop or threading.Event()
    received: queue.Queue = queue.Queue()
    keys = Session.load(session).client_keys() if session is not None else None
    receiver = threading.Thread(target=_receive, args=(endpoints, received, stop, deadline, keys), daemon=True,
                                name="recorder-receive")
    with Recorder(path, on_record) as recorder:
        if session is not None:
            recorder.attach_session(session)
        receiver.start()
        while receiver.is_alive() or not received.empty():
            try:
                frames, stamp = received.get(timeout=POLL_MS / 1000)
            except queue.Empty:
                recorder.flush_if_due()
                continue
            recorder.write(frames, stamp)
        return recorder.counts()


def check_endpoints(endpoints: list[str]) -> None:
    """InputError naming the first endpoint ZeroMQ cannot connect to (malformed, unknown
    transport), before any file is made: the receiving thread would only print a traceback."""
    with zmq.Context() as context, context.socket(zmq.SUB) as socket:
        socket.setsockopt(zmq.LINGER, 0)
        for endpoint in endpoints:
            try:
                socket.connect(endpoint)
            except zmq.ZMQError as e:
                raise InputError(f"{endpoint}: cannot connect ({zmq.strerror(e.errno)})") from None


def _receive(endpoints: list[str], received: queue.Queue, stop: threading.Event, deadline: float | None,
             keys: ClientKeys | None) -> None:
    """Puts (frames, arrival ns) of every message in `received` until stop or the deadline."""
    with zmq.Context() as context, transport.subscriber(context, endpoints, keys=keys) as socket:
        while not stop.is_set() and (deadline is None or time.monotonic() < deadline):
            if socket.poll(POLL_MS):
                frames = socket.recv_multipart()
                received.put((frames, time.time_ns()))
        for _ in range(transport.SUBSCRIBER_HWM):  # what had arrived when told to stop is recorded too
            if not socket.poll(0):
                break
            received.put((socket.recv_multipart(), time.time_ns()))
