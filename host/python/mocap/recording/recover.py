"""`mocap recover IN OUT`: a recording cut short or damaged written again as a whole,
indexed MCAP file (any MCAP reader's indexed access works on it: Foxglove, the `mcap`
library's make_reader(...).iter_messages()): every intact message (mocap.recording.reader),
its channels and schemas, and the intact attachments, in log-time order."""

from __future__ import annotations

from pathlib import Path

from mcap.writer import Writer

from mocap.errors import InputError
from mocap.recording import recorder
from mocap.recording.reader import Integrity, Recording


def recover(source: str | Path, target: str | Path) -> Integrity:
    """Writes the intact content of `source` to `target`; what `source` held and lost."""
    source, target = Path(source), Path(target)
    if target.exists() and target.resolve() == source.resolve():
        raise InputError(f"{target}: give another file to write to than the one to recover")
    with Recording(source) as recording, open(target, "wb") as out:
        writer = Writer(out, chunk_size=recorder.CHUNK_BYTES)
        writer.start(profile=recording.scan.profile, library="mocap recover")
        for a in recording.scan.attachments:
            if a.data is not None:
                writer.add_attachment(create_time=a.create_time, log_time=a.log_time, name=a.name,
                                      media_type=a.media_type, data=a.data)
        ids: dict[int, int] = {}  # the file's channel ids -> the new file's
        schemas: dict[int, int] = {0: 0}  # schema ids alike (0: no schema)
        for m in recording.messages(derived=True):
            if m.channel_id not in ids:
                ids[m.channel_id] = _register(writer, recording, m.channel_id, schemas)
            writer.add_message(ids[m.channel_id], log_time=m.log_time_ns, data=m.payload,
                               publish_time=m.publish_time_ns, sequence=m.sequence)
        writer.finish()
        return recording.integrity


def _register(writer: Writer, recording: Recording, channel_id: int, schemas: dict[int, int]) -> int:
    """The new file's id of a channel of the recording, registered with its schema."""
    channel = recording.channels[channel_id]
    if channel.schema_id not in schemas:
        schema = recording.scan.schemas[channel.schema_id]
        schemas[channel.schema_id] = writer.register_schema(schema.name, schema.encoding, schema.data)
    return writer.register_channel(channel.topic, channel.message_encoding, schemas[channel.schema_id],
                                   channel.metadata)
