"""Recordings cut short or damaged: read up to the last intact data, the loss counted; the
recorder's chunks closed in time; `recover` writes a whole indexed file."""

import json
import os
import random
import struct

import pytest
from mcap.reader import make_reader

from mocap import _core, cli, paths
from mocap.model import studio
from mocap.errors import InputError
from mocap.io.session import Session
from mocap.model.solver import imu_set_json
from mocap.net import wire
from mocap.recording import reader, recorder, recover

STEP_S = 1 / 64  # s (exact in binary), between the synthetic take's messages, on the recorder's clock and in log time


def take_messages(n: int) -> list[list[bytes]]:
    """n distinct messages: two cameras' keypoint frames (33 keypoints) and IMU batches in turn."""
    out, rng = [], random.Random(3)
    for i in range(n):
        if i % 3 == 2:
            sample = wire.ImuSample(sensor_id="pelvis", sample_time_ns=i, qw=1.0, az=9.81 + i * 1e-3)
            out.append(wire.encode(wire.ImuBatch(hub_id="hub0", sequence=i, send_time_ns=i, samples=[sample])))
        else:
            person = wire.KeypointPerson(x=[rng.uniform(0, 1920) for _ in range(33)],
                                         y=[rng.uniform(0, 1080) for _ in range(33)], confidence=[0.9] * 33)
            out.append(wire.encode(wire.KeypointFrame(camera_id=f"cam{i % 3}", frame_index=i, capture_time_ns=i,
                                                      persons=[person], keypoint_layout="coco17")))
    return out


@pytest.fixture
def session_file(tmp_path):
    """A session that mocapd would load (its rig and IMU set written beside it)."""
    (tmp_path / "rig.json").write_text(studio.ring_rig(8).to_json())
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    imus = _core.load_imu_sites(str(paths.IMU_SETS["13"]), skeleton)
    (tmp_path / "imus.json").write_text(json.dumps(imu_set_json(skeleton, imus)))
    return Session(str(paths.DEFAULT_SKELETON), "rig.json", str(paths.LAYOUTS / "blazepose33.json"), "imus.json",
                   ["tcp://127.0.0.1:5600"], "tcp://127.0.0.1:5700", base=tmp_path).save(tmp_path / "session.json")


@pytest.fixture
def take(tmp_path, session_file):
    """A 31 s recording (2,000 messages, session attached), chunks closed every 0.25 s of
    the recorder's clock; its path and (log time, payload) of each message."""
    clock, path, written = [0.0], tmp_path / "take.mcap", []
    with recorder.Recorder(path, chunk_s=0.25, clock=lambda: clock[0]) as r:
        r.attach_session(session_file)
        for i, frames in enumerate(take_messages(2000)):
            clock[0] = i * STEP_S
            assert r.write(frames, 10**9 + int(i * STEP_S * 1e9))
            written.append((10**9 + int(i * STEP_S * 1e9), frames[1]))
    return path, written


def got(path) -> list[tuple[int, bytes]]:
    return [(m.log_time_ns, m.payload) for m in reader.read(path)]


def summary_of(path):
    with open(path, "rb") as stream:
        return make_reader(stream).get_summary()


def test_chunks_close_after_chunk_s_and_reach_the_file_while_recording(tmp_path, take):
    path, written = take
    chunks = summary_of(path).chunk_indexes
    # Closed by the message that found the chunk due: 0.25 s (16 steps) after its first.
    assert [c.message_end_time - c.message_start_time for c in chunks[:-1]] == [0.25e9] * (len(chunks) - 1)
    assert len(chunks) == -(-2000 // 17)
    # While recording: what was written chunk_s ago is in the file, readable as it stands.
    clock = [0.0]
    live = recorder.Recorder(tmp_path / "live.mcap", chunk_s=0.25, clock=lambda: clock[0])
    try:
        for i, frames in enumerate(take_messages(30)):
            clock[0] = i * STEP_S
            live.write(frames, i)
        assert got(tmp_path / "live.mcap") == [(i, f[1]) for i, f in enumerate(take_messages(30)[:17])]
        clock[0] = 0.6
        live.flush_if_due()  # idle: the open chunk is due
        assert len(got(tmp_path / "live.mcap")) == 30
    finally:
        live.close()


@pytest.mark.parametrize("cut", [0.1, 0.5, 0.99, "index"])
def test_a_cut_recording_gives_every_message_of_its_intact_chunks(take, tmp_path, cut):
    path, written = take
    data = path.read_bytes()
    summary = summary_of(path)
    end = summary_start(data) if cut == "index" else int(len(data) * cut)  # "index": only the end index is missing
    (tmp_path / "cut.mcap").write_bytes(data[:end])
    whole = [c for c in summary.chunk_indexes if c.chunk_start_offset + c.chunk_length <= end]
    expected = [w for w in written if w[0] <= max(c.message_end_time for c in whole)]
    with reader.Recording(tmp_path / "cut.mcap") as recording:
        assert [(m.log_time_ns, m.payload) for m in recording.messages()] == expected
        integrity = recording.integrity
        assert recording.session(tmp_path) == tmp_path / "session.json"  # attached at the start
    assert not integrity.complete and integrity.intended_s is None and integrity.lost_s is None
    assert integrity.chunks == len(whole) and integrity.messages == len(expected)
    assert integrity.recovered_s == pytest.approx((expected[-1][0] - expected[0][0]) * 1e-9)
    assert "cut short" in integrity.describe()
    with pytest.raises(Exception):  # what the indexed readers did with it: refused
        list(make_reader(open(tmp_path / "cut.mcap", "rb")).iter_messages())


def summary_start(data: bytes) -> int:
    """Where the summary section starts (the footer's first field)."""
    return struct.unpack_from("<Q", data, len(data) - 8 - 20)[0]


def test_a_damaged_chunk_is_skipped_and_counted_the_rest_read(take, tmp_path):
    path, written = take
    data = bytearray(path.read_bytes())
    chunk = summary_of(path).chunk_indexes[40]
    for k in (100, 101, 160):  # inside its compressed records
        data[chunk.chunk_start_offset + k] ^= 0x5A
    (tmp_path / "bad.mcap").write_bytes(data)
    inside = [w for w in written if chunk.message_start_time <= w[0] <= chunk.message_end_time]
    assert got(tmp_path / "bad.mcap") == [w for w in written if w not in inside]
    with reader.Recording(tmp_path / "bad.mcap") as recording:
        integrity = recording.integrity
    assert integrity.complete and sum(integrity.chunks_skipped.values()) == 1 and integrity.chunks == 117
    assert integrity.intended_s == pytest.approx(1999 * STEP_S)
    assert integrity.lost_s == pytest.approx((chunk.message_end_time - chunk.message_start_time) * 1e-9)
    assert not integrity.intact and "1 damaged chunks skipped" in integrity.describe()


def test_a_damaged_record_length_loses_that_chunk_only(take, tmp_path):
    """The framing found again: the next chunk that passes its checks."""
    path, written = take
    data = bytearray(path.read_bytes())
    chunk = summary_of(path).chunk_indexes[10]
    data[chunk.chunk_start_offset + 1:chunk.chunk_start_offset + 9] = struct.pack("<Q", 2**62)
    (tmp_path / "bad.mcap").write_bytes(data)
    inside = [w for w in written if chunk.message_start_time <= w[0] <= chunk.message_end_time]
    assert got(tmp_path / "bad.mcap") == [w for w in written if w not in inside]
    with reader.Recording(tmp_path / "bad.mcap") as recording:
        assert recording.integrity.bytes_damaged >= chunk.chunk_length and recording.integrity.chunks == 117


def test_a_damaged_attached_session_is_refused_by_name(take, tmp_path):
    path, written = take
    data = bytearray(path.read_bytes())
    index = next(a for a in summary_of(path).attachment_indexes if a.name == "session/rig.json")
    data[index.offset + index.length - 40] ^= 0x01  # in the rig's JSON
    (tmp_path / "bad.mcap").write_bytes(data)
    with reader.Recording(tmp_path / "bad.mcap") as recording:
        assert recording.integrity.attachments_damaged == ["session/rig.json"]
        with pytest.raises(InputError, match=r"bad.mcap: the attached session is damaged \(attachment "
                                             r"session/rig.json fails its CRC check\); give the session"):
            recording.session(tmp_path / "out")
    assert got(tmp_path / "bad.mcap") == written  # the messages are intact


def test_recover_writes_a_whole_indexed_file(take, tmp_path, capsys):
    path, written = take
    data = path.read_bytes()
    (tmp_path / "cut.mcap").write_bytes(data[:len(data) // 2])
    assert cli.main(["recover", str(tmp_path / "cut.mcap"), str(tmp_path / "fixed.mcap")]) == 0
    printed = json.loads(capsys.readouterr().out)
    kept = got(tmp_path / "cut.mcap")
    assert printed["integrity"]["messages"] == len(kept) > 900 and not printed["integrity"]["complete"]
    # An independent reader, through the index (summary, chunk indexes) alone.
    with open(tmp_path / "fixed.mcap", "rb") as stream:
        indexed = make_reader(stream)
        assert indexed.get_summary().statistics.message_count == len(kept)
        assert [(m.log_time, m.data) for _, _, m in indexed.iter_messages(log_time_order=True)] == kept
        assert {a.name for a in indexed.iter_attachments()} >= {"session/session.json", "session/rig.json"}
    with reader.Recording(tmp_path / "fixed.mcap") as fixed:
        assert fixed.integrity.intact
    with pytest.raises(InputError, match="another file"):
        recover.recover(path, path)


def test_random_damage_never_raises_and_never_invents_a_message(take, tmp_path):
    """Flipped bits, overwritten runs, cuts: every message read is one that was written, in
    order; nothing but InputError (a damaged magic) comes out."""
    path, written = take
    data, rng = path.read_bytes(), random.Random(7)
    (tmp_path / "s").mkdir()
    for trial in range(150):
        damaged = bytearray(data)
        for _ in range(rng.randrange(1, 6)):
            at = rng.randrange(len(damaged))
            damaged[at:at + rng.choice((1, 8, 300))] = rng.randbytes(rng.choice((1, 8, 300)))
        if trial % 3 == 0:
            damaged = damaged[:rng.randrange(len(damaged))]
        (tmp_path / "d.mcap").write_bytes(damaged)
        try:
            with reader.Recording(tmp_path / "d.mcap", warn=False) as recording:
                read = [(m.log_time_ns, m.payload) for m in recording.messages()]
                recording.integrity.describe()
                try:
                    recording.session(tmp_path / "s")
                except InputError:
                    pass
        except InputError:
            assert damaged[:8] != data[:8]
            continue
        positions = {w: i for i, w in enumerate(written)}
        assert all(r in positions for r in read)
        assert [positions[r] for r in read] == sorted(positions[r] for r in read)


def test_what_is_no_recording_file_is_refused_without_waiting(tmp_path):
    (tmp_path / "empty.mcap").write_bytes(b"")
    with pytest.raises(InputError, match="empty"):
        reader.Recording(tmp_path / "empty.mcap")
    os.mkfifo(tmp_path / "fifo.mcap")  # opening it would wait for a writer
    with pytest.raises(InputError, match="no such recording file"):
        reader.Recording(tmp_path / "fifo.mcap")
