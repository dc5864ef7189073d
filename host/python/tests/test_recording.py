import random
import struct
import socket
import threading

import pytest
import zmq
from google.protobuf import descriptor_pb2, descriptor_pool, json_format, message_factory
from mcap.reader import make_reader

from mocap import cli
from mocap.net import transport, wire
from mocap.recording import reader, recorder, replay

TIMEOUT_S = 30.0  # bound on waits for the network; generous for loaded machines, never a measured duration


def stream_messages() -> list:
    """Keypoints of two cameras, IMU batches, a pose, a health report and a calibration, in
    capture order."""
    person = wire.KeypointPerson(x=[10.5, 20.25], y=[30.0, 40.0], confidence=[0.9, 0.0], track_id=3)
    cameras = [wire.KeypointFrame(camera_id=f"cam{i % 2}", frame_index=i // 2, capture_time_ns=1_000 + i,
                                  detected=i % 3 != 2, persons=[person] if i % 3 == 0 else [], keypoint_layout="coco17")
               for i in range(6)]
    sample = wire.ImuSample(sensor_id="pelvis", sample_time_ns=990, qw=1.0, az=9.81)
    imus = [wire.ImuBatch(hub_id="hub0", sequence=i, send_time_ns=2_000 + i, samples=[sample]) for i in range(3)]
    pose = wire.PoseFrame(capture_time_ns=1_000, frame_index=7, theta=[0.1] * 66, cameras=["cam0", "cam1"])
    health = wire.Health(source="host", time_ns=3_000, latency_p50_ms=4.5)
    calibration = wire.Calibration(source="calibrator", valid_from_ns=4_000, skeleton_json="{}", imus_json="{}",
                                   layout_json="{}")
    return cameras[:3] + imus[:2] + [pose] + cameras[3:] + [imus[2], health, calibration]


def malformed_frames() -> dict[str, list[bytes]]:
    nan_person = wire.KeypointPerson(x=[float("nan")], y=[1.0], confidence=[0.5])
    return {
        "not_finite": wire.encode(wire.KeypointFrame(camera_id="cam0", persons=[nan_person])),
        "wrong_version": [b"mocap.v2.KeypointFrame", wire.KeypointFrame(camera_id="cam0").SerializeToString()],
        "undecodable": [b"mocap.v1.ImuBatch", b"\xff\xff\xff"],
    }


def topic(message) -> str:
    return recorder.topic_and_time(message)[0]


def expected_topics(messages) -> list[str]:
    return [topic(m) for m in messages]


@pytest.fixture
def recorded(tmp_path):
    """A recording of stream_messages() written with shuffled log times, malformed frames between them."""
    messages = stream_messages()
    log_times = [1_000_000 * (i + 1) for i in range(len(messages))]
    order = list(range(len(messages)))
    random.Random(0).shuffle(order)
    path = tmp_path / "take.mcap"
    with recorder.Recorder(path) as rec:
        for k, i in enumerate(order):
            assert rec.write(wire.encode(messages[i]), log_times[i])
            if k % 3 == 0:
                for frames in malformed_frames().values():
                    assert not rec.write(frames, log_times[i])
    return path, messages, log_times, rec


def test_read_gives_back_the_well_formed_messages_in_log_time_order(recorded):
    path, messages, log_times, rec = recorded
    got = list(reader.read(path))
    assert [(m.log_time_ns, m.topic, m.type_name, m.payload) for m in got] == [
        (t, topic(m), m.DESCRIPTOR.full_name, m.SerializeToString()) for t, m in zip(log_times, messages)]
    assert {m.topic for m in got} == {"/camera/cam0", "/camera/cam1", "/imu/hub0", "/pose", "/health/host",
                                      "/calibration/calibrator"}
    writes_with_malformed = len(range(0, len(messages), 3))
    assert rec.dropped == {reason: writes_with_malformed for reason in malformed_frames()}
    assert sum(rec.recorded.values()) == len(messages) and rec.recorded["/camera/cam1"] == 3


def test_recording_is_self_describing(recorded):
    path, messages, _, _ = recorded
    pool, added = descriptor_pool.DescriptorPool(), set()  # an empty pool: nothing from the generated modules
    with open(path, "rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        views = {"foxglove.FrameTransforms", "foxglove.SceneUpdate"}  # beside the PoseFrame (test_recording_foxglove)
        assert sorted(s.name for s in summary.schemas.values()) == sorted([*wire.TYPES, *views])
        for schema in summary.schemas.values():
            assert schema.encoding == "protobuf"
            for file in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file:  # dependencies first
                if file.name not in added:
                    pool.Add(file)
                    added.add(file.name)
        decoded = []
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            assert channel.message_encoding == "protobuf"
            cls = _message_class(pool.FindMessageTypeByName(schema.name))
            if schema.name not in views:
                decoded.append((channel.topic, message.publish_time, cls.FromString(message.data)))
    assert [(t, publish, as_dict(m)) for t, publish, m in decoded] == [
        (topic(m), recorder.topic_and_time(m)[1], as_dict(m)) for m in messages]


def _message_class(descriptor):
    if hasattr(message_factory, "GetMessageClass"):  # protobuf >= 4.22
        return message_factory.GetMessageClass(descriptor)
    return message_factory.MessageFactory(descriptor.file.pool).GetPrototype(descriptor)


def as_dict(message) -> dict:
    return json_format.MessageToDict(message, preserving_proto_field_name=True)


def test_record_over_zeromq_keeps_everything_sent_after_joining(tmp_path):
    path = tmp_path / "live.mcap"
    joined, ended, stop = threading.Event(), threading.Event(), threading.Event()
    markers = {"/health/warmup": joined, "/health/end": ended}
    results = []
    with zmq.Context() as context, transport.publisher(context, "tcp://127.0.0.1:*") as publisher:
        endpoint = publisher.getsockopt_string(zmq.LAST_ENDPOINT)
        thread = threading.Thread(target=lambda: results.append(recorder.record(
            [endpoint], path, stop=stop, on_record=lambda t, _: markers[t].set() if t in markers else None)))
        thread.start()
        try:
            for _ in range(int(TIMEOUT_S / 0.01)):  # warm-up: until the recorder has seen a message
                publisher.send_multipart(wire.encode(wire.Health(source="warmup")))
                if joined.wait(0.01):
                    break
            assert joined.is_set(), "the recorder never received the warm-up messages"
            for message in stream_messages():
                publisher.send_multipart(wire.encode(message))
            for frames in malformed_frames().values():
                publisher.send_multipart(frames)
            publisher.send_multipart(wire.encode(wire.Health(source="end")))
            assert ended.wait(TIMEOUT_S), "the end marker was not recorded"
        finally:
            stop.set()
            thread.join()
    got = [m for m in reader.read(path) if m.topic not in markers]
    assert [(m.topic, m.payload) for m in got] == [(topic(m), m.SerializeToString()) for m in stream_messages()]
    assert results[0].dropped == {reason: 1 for reason in malformed_frames()}
    assert results[0].recorded["/health/end"] == 1 and results[0].recorded["/camera/cam0"] == 3


def free_tcp_endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp://127.0.0.1:{s.getsockname()[1]}"


@pytest.mark.parametrize("speed, topics, kept", [
    (None, None, ("/camera/", "/imu/", "/calibration/")),  # the default: the host's inputs, as fast as possible
    (50.0, None, ("/camera/", "/imu/", "/calibration/")),  # following the 1 ms log-time gaps at 50x
    (None, ["/pose", "/health/*"], ("/pose", "/health/")),
])
def test_replay_sends_the_chosen_topics_in_order(recorded, speed, topics, kept):
    path, messages, _, _ = recorded
    expected = [wire.encode(m) for m in messages if topic(m).startswith(kept)]
    assert 0 < len(expected) < len(messages)
    endpoint, results = free_tcp_endpoint(), []
    with zmq.Context() as context, transport.subscriber(context, [endpoint]) as subscriber:
        thread = threading.Thread(target=lambda: results.append(
            replay.replay(path, endpoint, speed, topics, wait_for_subscribers=TIMEOUT_S)))
        thread.start()
        try:
            got = [subscriber.recv_multipart() for _ in expected if subscriber.poll(TIMEOUT_S * 1000)]
        finally:
            thread.join()
    assert got == expected  # the skipped topics lie between these in log time: none was sent
    assert results == [len(expected)]


def test_restamping_moves_every_input_time_the_host_reads(recorded):
    """`replay --restamp`: capture, sample, send times and a calibration's valid_from move
    by the same offset, so a live host applies a recorded calibration where it was applied."""
    path, *_ = recorded
    offset = 10**12
    for m in reader.read(path):
        if not m.topic.startswith(("/camera/", "/imu/", "/calibration/")):
            continue
        before, after = wire.TYPES[m.type_name].FromString(m.payload), wire.TYPES[m.type_name].FromString(
            replay._shifted(m, offset))
        if isinstance(before, wire.KeypointFrame):
            assert after.capture_time_ns - before.capture_time_ns == offset
        elif isinstance(before, wire.ImuBatch):
            assert [b.sample_time_ns + offset for b in before.samples] == [a.sample_time_ns for a in after.samples]
        else:
            assert after.valid_from_ns - before.valid_from_ns == offset and after.skeleton_json == before.skeleton_json


def test_cli_replay_of_a_file_that_is_not_mcap_is_an_error(tmp_path, capsys):
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not an mcap file")
    assert cli.main(["replay", str(bad), "--bind", free_tcp_endpoint(), "--max-speed"]) == 2
    assert "not an MCAP file" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["/etc/passwd", "../skeleton.json", "missing.json"])
def test_an_attached_session_may_name_only_its_attachments(tmp_path, name):
    import json

    from mocap.errors import InputError

    session = {"format": "mocap.session/1", "skeleton": name, "rig": "rig.json", "layout": "layout.json",
               "imus": "imus.json", "inputs": ["tcp://127.0.0.1:5600"], "output": "tcp://*:5700"}
    path = tmp_path / "crafted.mcap"
    with recorder.Recorder(path) as r:
        for key in ("skeleton", "rig", "layout", "imus"):
            r._attach(f"session/{key}.json", b"{}")
        r._attach("session/session.json", json.dumps(session).encode())
    (tmp_path / "out").mkdir()
    with reader.Recording(path) as recording, pytest.raises(InputError) as e:
        recording.session(tmp_path / "out")
    assert str(e.value) == (f"{path}: the attached session names skeleton {name!r}, which is not one of its "
                            "attachments; give the session with --session")
    assert "root:" not in str(e.value)


def test_the_chunk_index_points_at_every_chunk_of_the_file(tmp_path):
    """The recorder keeps mcap's chunk index packed (recorder.PackedChunkIndexes): the index
    written at the end must still name each chunk where it is, with its times, so that an
    indexed reader finds every message."""
    clock = [0.0]
    messages = stream_messages() * 20
    with recorder.Recorder(tmp_path / "take.mcap", chunk_s=0.05, clock=lambda: clock[0]) as r:
        for k, message in enumerate(messages):
            clock[0] = 0.02 * k  # a chunk every 4 messages
            r.write(wire.encode(message), 10_000 + k)
    data = (tmp_path / "take.mcap").read_bytes()
    with open(tmp_path / "take.mcap", "rb") as f:
        mcap_reader = make_reader(f)
        summary = mcap_reader.get_summary()
        times = [m.log_time for _, c, m in mcap_reader.iter_messages(log_time_order=True)
                 if not c.topic.startswith("/skeleton/")]  # the PoseFrames' Foxglove views beside them
    assert summary.statistics.chunk_count == len(summary.chunk_indexes) >= len(messages) // 4
    assert times == list(range(10_000, 10_000 + len(messages)))
    for index in summary.chunk_indexes:
        assert data[index.chunk_start_offset] == 0x06  # a Chunk record's opcode
        start, end = struct.unpack_from("<QQ", data, index.chunk_start_offset + 9)
        assert (start, end) == (index.message_start_time, index.message_end_time)
