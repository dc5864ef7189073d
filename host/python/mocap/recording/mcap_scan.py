"""An MCAP file walked record by record from its start, trusting only what a check covers,
so that a file cut short (a recorder killed, a disk full) or damaged (flipped bits) gives
every intact message before the damage and after it (mocap.recording.reader reads them).

- A chunk counts when its records decompress to its stated size and match its CRC; its
  messages' times are then taken from the records, not from its header (outside the CRC).
  A chunk that fails is skipped and counted by reason.
- An attachment counts when it matches its CRC; one that does not is listed as damaged.
- The summary section (schemas, channels, statistics) counts when the footer's CRC matches.
- A record header that cannot be right (an opcode MCAP reserves, a length past the end of
  the file) means the framing is lost there: the walk searches on for the next chunk that
  passes its checks (a false one would need a matching CRC) and goes on from it, counting
  the bytes in between; when there is none, the rest of the file is what was cut.
"""

from __future__ import annotations

import collections
import dataclasses
import io
import struct
import zlib
from collections.abc import Iterator

import lz4.frame
import zstandard
from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.records import Channel, Schema, Statistics

MAGIC = b"\x89MCAP0\r\n"
MAX_CHUNK_BYTES = 1 << 30  # a chunk claiming more is refused (a damaged size field), not decompressed
HEADER, FOOTER, SCHEMA, CHANNEL, MESSAGE, CHUNK = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06
ATTACHMENT, STATISTICS, DATA_END = 0x09, 0x0B, 0x0F
KNOWN = set(range(0x01, 0x10))  # 0x00 and 0x10-0x7f are reserved; 0x80-0xff are private records
RECORD = struct.Struct("<BQ")  # opcode, content length
CHUNK_HEAD = struct.Struct("<QQQI")  # message start and end time, uncompressed size and CRC
MESSAGE_HEAD = struct.Struct("<HIQQ")  # channel id, sequence, log time, publish time
U32, U64 = struct.Struct("<I"), struct.Struct("<Q")


@dataclasses.dataclass
class Block:
    """Messages that passed their checks: a chunk's, or one message outside any chunk."""
    offset: int  # of its record
    end: int
    first_ns: int  # log times, from the messages themselves
    last_ns: int
    channels: collections.Counter  # messages per channel id
    chunk: bool = True


@dataclasses.dataclass
class Attachment:
    name: str
    media_type: str
    log_time: int
    create_time: int
    data: bytes | None  # None: damaged (problem says how)
    problem: str = ""


@dataclasses.dataclass
class Scan:
    size: int  # of the file, bytes
    profile: str = ""
    blocks: list[Block] = dataclasses.field(default_factory=list)
    schemas: dict[int, Schema] = dataclasses.field(default_factory=dict)
    channels: dict[int, Channel] = dataclasses.field(default_factory=dict)
    attachments: list[Attachment] = dataclasses.field(default_factory=list)
    skipped: collections.Counter = dataclasses.field(default_factory=collections.Counter)  # chunks, by reason
    skipped_spans: list[tuple[int, int]] = dataclasses.field(default_factory=list)  # their headers' log times
    damaged_bytes: int = 0  # passed over to find the framing again
    tail_bytes: int = 0  # after the last intact record, in which no intact record was found
    statistics: Statistics | None = None  # from a summary that passed its CRC
    complete: bool = False  # footer, closing magic and summary CRC all there and right


def scan(mm) -> Scan:
    """Walks `mm` (the file's bytes: an mmap or bytes that start with MAGIC)."""
    return _Walk(mm).run()


def records(data, start: int = 0, end: int | None = None) -> Iterator[tuple[int, int, int]]:
    """(opcode, content start, content end) of each record in data[start:end]; ValueError
    when one runs past the end."""
    end = len(data) if end is None else end
    while start < end:
        if start + RECORD.size > end:
            raise ValueError("a record header runs past the end")
        opcode, length = RECORD.unpack_from(data, start)
        content = start + RECORD.size
        if length > end - content:
            raise ValueError("a record runs past the end")
        yield opcode, content, content + length
        start = content + length


def chunk_data(mm, offset: int, end: int) -> tuple[bytes | None, str]:
    """The decompressed records of the chunk record at mm[offset:end], or None and the check it failed."""
    content = mm[offset + RECORD.size:end]
    if len(content) < CHUNK_HEAD.size + U32.size:
        return None, "malformed"
    _, _, size, crc = CHUNK_HEAD.unpack_from(content)
    (name_length,) = U32.unpack_from(content, CHUNK_HEAD.size)
    body = CHUNK_HEAD.size + U32.size + name_length + U64.size
    if body > len(content):
        return None, "malformed"
    compression = bytes(content[CHUNK_HEAD.size + U32.size:body - U64.size])
    (records_length,) = U64.unpack_from(content, body - U64.size)
    if records_length > len(content) - body:
        return None, "malformed"
    if size > MAX_CHUNK_BYTES:
        return None, "too large"
    try:
        data = _decompress(compression, content[body:body + records_length], size)
    except (zstandard.ZstdError, RuntimeError, ValueError):
        return None, "not decompressible"
    if data is None:
        return None, "unknown compression"
    if len(data) != size:
        return None, "size"
    if crc != 0 and zlib.crc32(data) != crc:
        return None, "crc"
    return data, ""


def _decompress(compression: bytes, data: bytes, size: int) -> bytes | None:
    """At most size + 1 bytes (a stream longer than stated fails the size check, unread)."""
    if compression == b"":
        return data
    if compression == b"zstd":
        return zstandard.ZstdDecompressor().stream_reader(io.BytesIO(data)).read(size + 1)
    if compression == b"lz4":
        return lz4.frame.LZ4FrameDecompressor().decompress(data, max_length=size + 1)
    return None


def block_messages(mm, block: Block) -> Iterator[tuple[int, int, int, int, bytes]]:
    """(channel id, sequence, log time, publish time, data) of a block's messages, in file order."""
    opcode, length = RECORD.unpack_from(mm, block.offset)
    if opcode == MESSAGE:
        data, start, end = mm, block.offset + RECORD.size, block.end
    else:
        data, _ = chunk_data(mm, block.offset, block.end)
        if data is None:  # checked when scanned: the file changed since
            return
        start, end = 0, len(data)
    for opcode, start, end in records(data, start, end):
        if opcode == MESSAGE:
            yield (*MESSAGE_HEAD.unpack_from(data, start), bytes(data[start + MESSAGE_HEAD.size:end]))


def _parse(cls, content: bytes):
    """A schema, channel or statistics record read by mcap's own classes; None if malformed."""
    try:
        return cls.read(ReadDataStream(io.BytesIO(content)))
    except (McapError, struct.error, UnicodeDecodeError, ValueError):
        return None


def _next_chunk(mm, start: int) -> int | None:
    """The offset of the next chunk at or after `start` that passes its checks."""
    while (start := mm.find(bytes([CHUNK]), start)) >= 0:
        if start + RECORD.size <= len(mm):
            _, length = RECORD.unpack_from(mm, start)
            if length <= len(mm) - start - RECORD.size and chunk_data(mm, start, start + RECORD.size + length)[0]:
                return start
        start += 1
    return None


class _Walk:
    def __init__(self, mm):
        self.mm, self.scan = mm, Scan(size=len(mm))
        self.good_end = len(MAGIC)  # the end of the last record whose framing held
        self.in_summary = False
        self.summary: dict = {"schemas": {}, "channels": {}, "statistics": None}

    def run(self) -> Scan:
        pos, previous = len(MAGIC), len(MAGIC)
        while pos < len(self.mm):
            end = self._plausible(pos)
            if end is None:  # framing lost: this record is cut or damaged, or the previous one's length was
                found = None if self.in_summary else _next_chunk(self.mm, previous + 1)
                if found is None:
                    break
                self.scan.damaged_bytes += max(0, found - self.good_end)
                pos = previous = found
                continue
            opcode = self.mm[pos]
            if opcode == FOOTER:
                self._footer(pos, end)
                self.good_end = len(self.mm) if self.scan.complete else end
                break
            self._record(opcode, pos, end)
            self.good_end, previous, pos = end, pos, end
        self.scan.tail_bytes = len(self.mm) - self.good_end
        return self.scan

    def _plausible(self, pos: int) -> int | None:
        """The end of the record at pos, or None when its header cannot be right."""
        if pos + RECORD.size > len(self.mm):
            return None
        opcode, length = RECORD.unpack_from(self.mm, pos)
        if (opcode not in KNOWN and opcode < 0x80) or length > len(self.mm) - pos - RECORD.size:
            return None
        return pos + RECORD.size + length

    def _record(self, opcode: int, pos: int, end: int) -> None:
        content = slice(pos + RECORD.size, end)
        if opcode == CHUNK:
            self._chunk(pos, end)
        elif opcode == MESSAGE and end - pos >= RECORD.size + MESSAGE_HEAD.size:
            channel, _, log_time, _ = MESSAGE_HEAD.unpack_from(self.mm, pos + RECORD.size)
            self.scan.blocks.append(Block(pos, end, log_time, log_time, collections.Counter([channel]), False))
        elif opcode == ATTACHMENT:
            self.scan.attachments.append(_attachment(self.mm[content]))
        elif opcode in (SCHEMA, CHANNEL, STATISTICS):
            self._definition(opcode, self.mm[content])
        elif opcode == HEADER:
            header = self.mm[content]
            (length,) = U32.unpack_from(header) if len(header) >= U32.size else (0,)
            self.scan.profile = bytes(header[U32.size:U32.size + length]).decode("utf-8", "replace")
        elif opcode == DATA_END:
            self.in_summary = True

    def _definition(self, opcode: int, content: bytes) -> None:
        """A schema or channel: in the data section, taken as it is (in a chunk its CRC checked
        it); in the summary, kept until the footer's CRC says whether it counts."""
        record = _parse({SCHEMA: Schema, CHANNEL: Channel, STATISTICS: Statistics}[opcode], content)
        if record is None or (opcode == STATISTICS and not self.in_summary):
            return
        if opcode == STATISTICS:
            self.summary["statistics"] = record
            return
        key = "schemas" if opcode == SCHEMA else "channels"
        target = self.summary[key] if self.in_summary else getattr(self.scan, key)
        target.setdefault(record.id, record)

    def _chunk(self, pos: int, end: int) -> None:
        data, problem = chunk_data(self.mm, pos, end)
        if data is not None:
            try:
                self._chunk_records(pos, end, data)
                return
            except ValueError:
                problem = "malformed"
        self.scan.skipped[problem] += 1
        if end - pos >= RECORD.size + 16:
            self.scan.skipped_spans.append(CHUNK_HEAD.unpack_from(self.mm, pos + RECORD.size)[:2])

    def _chunk_records(self, pos: int, end: int, data: bytes) -> None:
        channels, times, definitions = collections.Counter(), [], []
        for opcode, start, stop in records(data):
            if opcode == MESSAGE:
                if stop - start < MESSAGE_HEAD.size:
                    raise ValueError("a message shorter than its header")
                channel, _, log_time, _ = MESSAGE_HEAD.unpack_from(data, start)
                channels[channel] += 1
                times.append(log_time)
            elif opcode in (SCHEMA, CHANNEL):
                definitions.append((opcode, data[start:stop]))
        for opcode, content in definitions:
            self._definition(opcode, content)
        if times:
            self.scan.blocks.append(Block(pos, end, min(times), max(times), channels))

    def _footer(self, pos: int, end: int) -> None:
        """The summary counts when the footer's CRC covers it; the file is complete when the
        closing magic follows."""
        content = self.mm[pos + RECORD.size:end]
        if len(content) < 20:
            return
        summary_start, _, crc = struct.unpack_from("<QQI", content)
        summary = self.mm[summary_start:pos] if 0 < summary_start <= pos else b""
        covered = zlib.crc32(self.mm[pos:pos + RECORD.size + 16], zlib.crc32(summary))
        intact = summary_start <= pos and (crc == 0 or covered == crc)
        if intact:
            for key in ("schemas", "channels"):
                for record_id, record in self.summary[key].items():
                    getattr(self.scan, key).setdefault(record_id, record)
            self.scan.statistics = self.summary["statistics"]
        self.scan.complete = intact and self.mm[end:end + len(MAGIC)] == MAGIC


def _attachment(content: bytes) -> Attachment:
    """An attachment record's fields, its data None when it fails its CRC or does not parse."""
    try:
        log_time, create_time = struct.unpack_from("<QQ", content)
        at = 16
        fields = []
        for _ in range(2):  # name, media type
            (length,) = U32.unpack_from(content, at)
            fields.append(bytes(content[at + U32.size:at + U32.size + length]).decode("utf-8", "replace"))
            at += U32.size + length
        (length,) = U64.unpack_from(content, at)
        data = bytes(content[at + U64.size:at + U64.size + length])
        (crc,) = U32.unpack_from(content, at + U64.size + length)
    except struct.error:
        return Attachment("", "", 0, 0, None, "malformed")
    if len(data) != length:
        return Attachment(fields[0], fields[1], log_time, create_time, None, "malformed")
    if crc != 0 and zlib.crc32(content[:at + U64.size + length]) != crc:
        return Attachment(fields[0], fields[1], log_time, create_time, None, "fails its CRC check")
    return Attachment(fields[0], fields[1], log_time, create_time, data)
