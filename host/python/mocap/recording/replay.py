"""Replaying a recording on ZeroMQ: its messages published as [type, payload], following
their log times (or as fast as the subscribers take them), restamped to now if asked."""

from __future__ import annotations

import fnmatch
import time
from collections.abc import Iterable
from pathlib import Path

import zmq

from mocap.errors import InputError
from mocap.net import transport, wire
from mocap.net.keys import ServerKeys
from mocap.recording import reader
from mocap.recording.reader import RecordedMessage

INPUT_TOPICS = ("/camera/*", "/imu/*", "/calibration/*")  # what `replay` sends by default: the host's inputs
BACKPRESSURE_SLEEP_S = 0.001  # `replay`'s pause while a subscriber's queue is full
REPLAY_LINGER_MS = 10_000  # time the last queued messages get to reach slow subscribers

def replay(recording: str | Path | reader.Recording, endpoint: str, speed: float | None = 1.0, topics: Iterable[str] | None = None,
           wait_for_subscribers: float = 1.0, restamp: bool = False, keys: ServerKeys | None = None) -> int:
    """Publishes the recorded messages on `endpoint` as [type, payload]; returns how many were sent.

    topics: fnmatch patterns of the topics to send (default INPUT_TOPICS, the host's inputs).
    speed: times real time, following the log-time gaps; None sends as fast as the subscribers take
    them. Pacing never blocks inside ZeroMQ: the socket refuses a message at a subscriber's
    high-water mark (XPUB_NODROP) and the replay sleeps BACKPRESSURE_SLEEP_S and retries, so a slow
    subscriber slows the replay down instead of losing messages.
    Sending starts when a first subscriber has joined, or after wait_for_subscribers seconds.
    A recording cut short or damaged is replayed as far as its intact chunks go (recording:
    a file, or a reader.Recording open already).
    restamp (with a speed): every capture, sample and send time is moved by the time between
    the recording and now, so a live host takes the replay for a take happening now (its
    synchroniser waits for inputs by their capture time); the recording's own bytes otherwise.
    keys: publish as a CURVE server with this identity (the session of the mocapd it feeds
    lists its public key for the endpoint).
    """
    if restamp and speed is None:
        raise InputError("restamping needs a replay speed: as fast as possible has no 'now'")
    if speed is not None and not speed > 0:
        raise InputError(f"replay speed must be positive, not {speed}")
    if not isinstance(recording, reader.Recording):  # a path
        with reader.Recording(recording) as opened:
            return replay(opened, endpoint, speed, topics, wait_for_subscribers, restamp, keys)
    patterns = tuple(INPUT_TOPICS if topics is None else topics)
    messages = (m for m in recording.messages() if any(fnmatch.fnmatchcase(m.topic, p) for p in patterns))
    with zmq.Context() as context, _replay_socket(context, endpoint, keys) as socket:
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
    shift(message, offset_ns)
    return message.SerializeToString()  # closing the socket then waits (LINGER) for the queued messages to leave


def shift(message, offset_ns: int) -> None:
    """Moves the times a host reads of an input message (capture, sample and send times; a
    calibration's valid_from) by offset_ns, in place; other messages are left as they are."""
    if isinstance(message, wire.KeypointFrame):
        message.capture_time_ns += offset_ns
        message.send_time_ns += offset_ns if message.send_time_ns else 0
    elif isinstance(message, wire.ImuBatch):
        message.send_time_ns += offset_ns if message.send_time_ns else 0
        for sample in message.samples:
            sample.sample_time_ns += offset_ns
    elif isinstance(message, wire.Calibration):  # from the same moment of the take
        message.valid_from_ns += offset_ns


def _replay_socket(context: zmq.Context, endpoint: str, keys: ServerKeys | None) -> zmq.Socket:
    """A PUB socket that reports subscriptions and refuses (instead of dropping) at the high-water mark."""
    socket = context.socket(zmq.XPUB)
    if keys is not None:
        socket.curve_server = True
        socket.curve_secretkey = keys.pair.secret.encode()
    socket.setsockopt(zmq.SNDHWM, transport.PUBLISHER_HWM)
    socket.setsockopt(zmq.XPUB_NODROP, 1)
    socket.setsockopt(zmq.LINGER, REPLAY_LINGER_MS)
    try:
        socket.bind(endpoint)
    except zmq.ZMQError as e:  # a port in use, a malformed endpoint
        socket.close(0)
        raise InputError(f"{endpoint}: cannot publish there ({zmq.strerror(e.errno)})") from None
    return socket


def _send(socket: zmq.Socket, frames: list[bytes]) -> None:
    while True:
        try:
            socket.send_multipart(frames, zmq.NOBLOCK)
            return
        except zmq.Again:
            time.sleep(BACKPRESSURE_SLEEP_S)
