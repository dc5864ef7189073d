"""Reading recordings (mocap.recording.recorder's MCAP files): the messages in log-time
order, and the session attached to them."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

from mcap.exceptions import McapError
from mcap.reader import make_reader

from mocap.errors import InputError


@dataclasses.dataclass(frozen=True)
class RecordedMessage:
    log_time_ns: int
    topic: str
    type_name: str  # "mocap.v1.KeypointFrame", the ZeroMQ type frame
    payload: bytes


def read(path: str | Path) -> Iterator[RecordedMessage]:
    """The messages of a recording in log-time order."""
    with open(path, "rb") as stream:
        yield from messages(stream, str(path))


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


def messages(stream: BinaryIO, name: str) -> Iterator[RecordedMessage]:
    """The messages of an open MCAP stream in log-time order (name: for errors)."""
    try:
        reader = make_reader(stream)  # checks the magic now, not at the first message
    except McapError as e:
        raise InputError(f"{name}: not an MCAP file ({e})") from None
    return (RecordedMessage(message.log_time, channel.topic, schema.name if schema else "", message.data)
            for schema, channel, message in reader.iter_messages(log_time_order=True))
