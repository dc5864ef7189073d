"""Reading recordings (mocap.recording.recorder's MCAP files): the messages in log-time
order, the session attached to them, and what was lost when a file is cut short or damaged.

Every file is read the same way, whole or not (mocap.recording.mcap_scan: each chunk's and
attachment's CRC checked, the framing found again after damage): a recording whose recorder
was killed, or whose disk filled, gives every message of its intact chunks, and `Integrity`
says how much is missing. A damaged attached session is refused (InputError naming the
attachment); the session can then be given instead.
"""

from __future__ import annotations

import dataclasses
import heapq
import logging
import mmap
from collections.abc import Iterator
from pathlib import Path

from mocap.errors import InputError
from mocap.io.session import FILES, Session
from mocap.recording import foxglove, mcap_scan

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class RecordedMessage:
    log_time_ns: int
    topic: str
    type_name: str  # "mocap.v1.KeypointFrame", the ZeroMQ type frame
    payload: bytes
    publish_time_ns: int = 0
    sequence: int = 0
    channel_id: int = 0  # the file's


@dataclasses.dataclass(frozen=True)
class Integrity:
    """What of a recording could be read, and what was lost (the tools print it)."""
    complete: bool  # closed properly: its end index is there and checks out
    messages: int  # read
    chunks: int  # read
    chunks_skipped: dict[str, int]  # failed a check, by reason (crc, size, not decompressible, ...)
    chunks_intended: int | None  # per the end index, when it is there
    messages_lost: int  # of an unknown channel (its definition was in a skipped chunk)
    bytes_damaged: int  # passed over in the middle of the file to find the next intact chunk
    bytes_after_last_record: int  # at the end: the record the cut went through
    recovered_s: float  # log time from the first message read to the last
    intended_s: float | None  # the same per the end index, when it is there
    skipped_s: float  # log time the skipped chunks spanned, per their (unchecked) headers
    attachments_damaged: list[str]

    @property
    def lost_s(self) -> float | None:
        """Seconds of log time lost: the skipped chunks' and, when the intended span is
        known, what is missing at the ends. None when the file is cut and nothing says
        how long it was meant to be."""
        if self.intended_s is None:
            return None if not self.complete else self.skipped_s
        return max(0.0, self.intended_s - self.recovered_s) + self.skipped_s

    @property
    def intact(self) -> bool:
        return (self.complete and not self.chunks_skipped and not self.bytes_damaged and not self.messages_lost
                and not self.attachments_damaged and self.chunks_intended in (None, self.chunks))

    def as_dict(self) -> dict:
        return {**dataclasses.asdict(self), "lost_s": self.lost_s}

    def describe(self) -> str:
        """One line for a person: what was read and what is missing."""
        parts = [f"read {self.recovered_s:.2f} s of log time ({self.messages} messages in {self.chunks} chunks)"]
        if self.intended_s is not None:
            parts.append(f"of {self.intended_s:.2f} s recorded")
        if not self.complete:
            unknown = "; how long it was meant to be is unknown" if self.intended_s is None else ""
            parts.append(f"cut short or its end index damaged ({self.bytes_after_last_record} bytes after the last "
                         f"intact record{unknown})")
        if self.chunks_skipped:
            parts.append(f"{sum(self.chunks_skipped.values())} damaged chunks skipped "
                         f"({', '.join(f'{n} {why}' for why, n in self.chunks_skipped.items())}; "
                         f"{self.skipped_s:.2f} s)")
        if self.chunks_intended not in (None, self.chunks):
            parts.append(f"{self.chunks_intended - self.chunks} of the {self.chunks_intended} chunks written not read")
        if self.bytes_damaged:
            parts.append(f"{self.bytes_damaged} damaged bytes passed over")
        if self.messages_lost:
            parts.append(f"{self.messages_lost} messages of a channel defined in a lost chunk")
        if self.attachments_damaged:
            parts.append(f"damaged attachments: {', '.join(self.attachments_damaged)}")
        return "; ".join(parts)


class Recording:
    """A recording open for reading (a context manager): its integrity at once, its
    messages on demand (each chunk decompressed again as the log-time order reaches it)."""

    def __init__(self, path: str | Path, warn: bool = True):
        """warn: log what is lost (a warning) when the file is not intact."""
        self.path = Path(path)
        if not self.path.is_file():  # a FIFO would block the open; a folder is no recording
            raise InputError(f"{path}: no such recording file")
        self._file = open(self.path, "rb")
        try:
            self._mm = mmap.mmap(self._file.fileno(), 0, access=mmap.ACCESS_READ)
        except ValueError:  # an empty file cannot be mapped
            self._file.close()
            raise InputError(f"{path}: not an MCAP file (it is empty)") from None
        if self._mm[:len(mcap_scan.MAGIC)] != mcap_scan.MAGIC:
            self.close()
            raise InputError(f"{path}: not an MCAP file (it does not start with MCAP's magic bytes)")
        self.scan = mcap_scan.scan(self._mm)
        self.channels = {i: c for i, c in self.scan.channels.items() if c.schema_id in (0, *self.scan.schemas)}
        self.integrity = _integrity(self.scan, self.channels)
        if warn and not self.integrity.intact:
            log.warning("%s: %s", path, self.integrity.describe())

    def messages(self, derived: bool = False) -> Iterator[RecordedMessage]:
        """Every intact message in log-time order (file order among equal times); the views
        derived from the PoseFrames for Foxglove (mocap.recording.foxglove) only when `derived`."""
        blocks = sorted(self.scan.blocks, key=lambda b: (b.first_ns, b.offset))
        pending: list = []  # heap of (log time, n, message)
        n = 0
        for block in blocks:
            while pending and pending[0][0] < block.first_ns:  # no later block has an earlier message
                yield heapq.heappop(pending)[2]
            for channel_id, sequence, log_time, publish_time, data in mcap_scan.block_messages(self._mm, block):
                channel = self.channels.get(channel_id)
                if channel is not None and (derived or channel.topic not in foxglove.TOPICS):
                    schema = self.scan.schemas.get(channel.schema_id)
                    message = RecordedMessage(log_time, channel.topic, schema.name if schema else "", data,
                                              publish_time, sequence, channel_id)
                    heapq.heappush(pending, (log_time, n, message))
                    n += 1
        while pending:
            yield heapq.heappop(pending)[2]

    def session(self, folder: str | Path) -> Path | None:
        """Extracts the attached session into `folder`; its session file, or None when the
        recording has none. InputError when an attachment of it is damaged or missing."""
        attached = [a for a in self.scan.attachments if a.name.startswith("session/")]
        damaged = [a for a in self.scan.attachments if a.data is None]
        for a in damaged:
            if a.name.startswith("session/") or not a.name:
                raise InputError(f"{self.path}: the attached session is damaged (attachment "
                                 f"{a.name or 'with an unreadable name'} {a.problem}); give the session with --session")
        if attached and not any(a.name == "session/session.json" for a in attached):
            raise InputError(f"{self.path}: the attached session is incomplete (no session/session.json; the file "
                             "was cut or damaged there); give the session with --session")
        found = None
        for a in attached:
            target = Path(folder) / Path(a.name).name
            target.write_bytes(a.data)
            found = target if target.name == "session.json" else found
        if found is not None:
            self._check_session_files(found)
        return found

    def _check_session_files(self, session: Path) -> None:
        """The attached session may name only files attached beside it: a path elsewhere (absolute,
        `..`) would have a recording read the host's own files."""
        config = Session.load(session)
        named = [(key, getattr(config, key)) for key in FILES]
        named += [(f"suit {n}'s {key}", name) for n, suit in enumerate(config.suits) for key, name in suit.items()]
        for what, name in named:
            if name is not None and (Path(name).name != name or not (session.parent / name).is_file()):
                raise InputError(f"{self.path}: the attached session names {what} {name!r}, which is not one of "
                                 "its attachments; give the session with --session")

    def close(self) -> None:
        self._mm.close()
        self._file.close()

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *_) -> None:
        self.close()


def _integrity(scan: mcap_scan.Scan, channels: dict) -> Integrity:
    lost = sum(n for b in scan.blocks for channel, n in b.channels.items() if channel not in channels)
    first = min((b.first_ns for b in scan.blocks), default=0)
    last = max((b.last_ns for b in scan.blocks), default=0)
    stats = scan.statistics
    intended = None if stats is None or stats.message_count == 0 else stats.message_end_time - stats.message_start_time
    lo, hi = (stats.message_start_time, stats.message_end_time) if intended is not None else (first, last)
    skipped_ns = sum(end - start for start, end in scan.skipped_spans if lo <= start <= end <= hi)
    return Integrity(
        complete=scan.complete, messages=sum(sum(b.channels.values()) for b in scan.blocks) - lost,
        chunks=sum(b.chunk for b in scan.blocks),
        chunks_skipped=dict(scan.skipped), chunks_intended=None if stats is None else stats.chunk_count,
        messages_lost=lost, bytes_damaged=scan.damaged_bytes, bytes_after_last_record=scan.tail_bytes,
        recovered_s=(last - first) * 1e-9, intended_s=None if intended is None else intended * 1e-9,
        skipped_s=skipped_ns * 1e-9,
        attachments_damaged=[a.name or "(unreadable name)" for a in scan.attachments if a.data is None])


def read(path: str | Path) -> Iterator[RecordedMessage]:
    """The intact messages of a recording in log-time order."""
    with Recording(path) as recording:
        yield from recording.messages()


def read_session(path: str | Path, folder: str | Path) -> Path | None:
    """Extracts the session attached to a recording into `folder` (Recording.session)."""
    with Recording(path) as recording:
        return recording.session(folder)
