"""CURVE keys: `mocap keys` writes a key pair the readers take back; a bad key file or a malformed
key in a session is refused with an error that names it; over ZeroMQ a subscriber hears only the
publisher holding the key it expects, and a publisher admitting listed clients refuses the others."""

import dataclasses
import json
import os
import re
import stat
import subprocess
import sys
import threading
import time

import pytest
import zmq

from mocap import _core, paths
from mocap.errors import InputError
from mocap.io.session import CurveSettings, Session
from mocap.model import studio
from mocap.model.solver import imu_set_json
from mocap.net import keys, transport, wire


@pytest.fixture
def session(tmp_path) -> Session:
    """A session mocapd loads (an 8-camera ring, the 13-IMU set), its files beside it."""
    (tmp_path / "rig.json").write_text(studio.ring_rig(8).to_json())
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    imus = _core.load_imu_sites(str(paths.IMU_SETS["13"]), skeleton)
    (tmp_path / "imus.json").write_text(json.dumps(imu_set_json(skeleton, imus)))
    return Session(str(paths.DEFAULT_SKELETON), "rig.json", str(paths.LAYOUTS / "coco17.json"), "imus.json",
                   ["tcp://127.0.0.1:5600"], "tcp://127.0.0.1:5700", base=tmp_path)


def _pair(tmp_path, name):
    keys.make_keypair(tmp_path, name)
    return keys.read_secret(tmp_path / f"{name}.key")


def test_mocap_keys_writes_a_private_secret_and_its_public_key(tmp_path):
    out = subprocess.run([sys.executable, "-m", "mocap.cli", "keys", "--out", str(tmp_path / "k"), "--name", "cam_01"],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    made = json.loads(out.stdout)
    secret, public = tmp_path / "k" / "cam_01.key", tmp_path / "k" / "cam_01.pub"
    assert made["secret"] == str(secret) and made["public_key"] == public.read_text().strip()
    assert stat.S_IMODE(secret.stat().st_mode) == 0o600
    pair = keys.read_secret(secret)
    assert pair.public == made["public_key"] and keys.is_key(pair.secret) and pair.secret != pair.public
    again = subprocess.run([sys.executable, "-m", "mocap.cli", "keys", "--out", str(tmp_path / "k"), "--name", "cam_01"],
                           capture_output=True, text=True, timeout=60)
    assert again.returncode != 0 and "exists" in again.stderr  # a device's key is never replaced by accident
    assert keys.read_secret(secret) == pair


def test_a_bad_secret_key_file_is_refused_with_what_is_wrong(tmp_path):
    pair = _pair(tmp_path, "host")
    opened = tmp_path / "open.key"
    opened.write_text(pair.secret)
    os.chmod(opened, 0o644)
    with pytest.raises(keys.KeyFileError, match=r"readable by others \(mode 0644\): chmod 600"):
        keys.read_secret(opened)
    for name, text in (("short.key", pair.secret[:39]), ("quote.key", '"' + pair.secret[1:]), ("bin.key", "\xff" * 40)):
        path = tmp_path / name
        path.write_text(text)
        os.chmod(path, 0o600)
        with pytest.raises(keys.KeyFileError, match="is not a secret key"):
            keys.read_secret(path)
    with pytest.raises(keys.KeyFileError, match="cannot read secret key"):
        keys.read_secret(tmp_path / "none.key")
    assert keys.read_public(pair.public) == pair.public
    assert keys.read_public(str(tmp_path / "host.pub")) == pair.public
    with pytest.raises(keys.KeyFileError, match="neither a public key"):
        keys.read_public("nonsense")


def _keyed(session, tmp_path):
    host, box = _pair(tmp_path, "host"), _pair(tmp_path, "box")
    return dataclasses.replace(session, curve=CurveSettings("host.key", {session.inputs[0]: box.public})), host, box


def test_the_session_reads_its_keys_and_mocapd_reads_the_same(session, tmp_path):
    keyed, host, box = _keyed(session, tmp_path)
    path = keyed.save(tmp_path / "session.json")
    loaded = Session.load(path)
    assert loaded.curve == keyed.curve
    client = loaded.client_keys()
    assert client.pair == host and client.server(session.inputs[0]) == box.public
    assert client.server("tcp://127.0.0.1:5700") == host.public  # mocapd's output: the host's key
    _core.HostPipeline.load(str(path))  # mocapd's own reader takes it


@pytest.mark.parametrize("curve, message", [
    ({"host_key": "host.key", "inputs": {"tcp://127.0.0.1:5600": "x" * 39}}, "key of 'tcp://127.0.0.1:5600'"),
    ({"host_key": "host.key", "inputs": {"tcp://127.0.0.1:5600": "~" * 40}}, "key of 'tcp://127.0.0.1:5600'"),
    ({"host_key": "host.key", "inputs": {}}, "no key for input 'tcp://127.0.0.1:5600'"),
    ({"host_key": "host.key", "inputs": {"tcp://127.0.0.1:5600": "BOX", "tcp://box:1": "BOX"}},
     "'tcp://box:1', which is not an input"),
    ({"inputs": {"tcp://127.0.0.1:5600": "BOX"}}, "host_key"),
    ({"host_key": "host.key", "inputs": {"tcp://127.0.0.1:5600": "BOX"}, "subscribers": ["short"]},
     'subscriber "short" is not a public key'),
    ({"host_key": "host.key", "inputs": {"tcp://127.0.0.1:5600": "BOX"}, "server_key": "BOX"},
     "unknown curve key 'server_key'"),
])
def test_malformed_keys_are_refused_by_both_readers(session, tmp_path, curve, message):
    _, _, box = _keyed(session, tmp_path)
    data = session.to_json() | {"curve": json.loads(json.dumps(curve).replace('"BOX"', json.dumps(box.public)))}
    with pytest.raises(InputError, match=re.escape(message)):
        Session.from_json(data, tmp_path)
    (tmp_path / "bad.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match=re.escape(message)):
        _core.HostPipeline.load(str(tmp_path / "bad.json"))


def test_a_host_key_others_can_read_is_refused_by_both_readers(session, tmp_path):
    keyed, _, _ = _keyed(session, tmp_path)
    os.chmod(tmp_path / "host.key", 0o640)
    path = keyed.save(tmp_path / "session.json")
    with pytest.raises(InputError, match="readable by others"):
        Session.load(path).client_keys()
    with pytest.raises(ValueError, match="readable by others"):
        _core.HostPipeline.load(str(path))


def _received(sub, pub, n=10, polls=400):
    got = 0
    for _ in range(polls):
        pub.send(b"x")
        if sub.poll(5):
            while True:
                try:
                    sub.recv(zmq.NOBLOCK)
                    got += 1
                except zmq.Again:
                    break
        if got >= n:
            break
    return got


def test_a_subscriber_hears_only_the_publisher_holding_the_key_it_expects(tmp_path):
    host, box, stranger = _pair(tmp_path, "host"), _pair(tmp_path, "box"), _pair(tmp_path, "stranger")
    context = zmq.Context()
    endpoints = [f"tcp://127.0.0.1:{p}" for p in (_free(), _free())]
    # Two publishers of different keys on one socket: each connection takes its own server key.
    right = transport.publisher(context, endpoints[0], keys=keys.ServerKeys(box))
    wrong = transport.publisher(context, endpoints[1], keys=keys.ServerKeys(stranger))
    client = keys.ClientKeys(host, {endpoints[0]: box.public, endpoints[1]: box.public})
    sub = transport.subscriber(context, endpoints, keys=client)
    assert _received(sub, right) >= 10
    assert _received(sub, wrong, n=1, polls=100) == 0
    with pytest.raises(keys.KeyFileError, match="no key for tcp://127.0.0.1:1"):
        transport.subscriber(context, ["tcp://127.0.0.1:1"], keys=keys.ClientKeys(host, {}))
    for s in (sub, right, wrong):
        s.close(linger=0)
    context.term()


def test_a_box_admitting_the_host_refuses_other_subscribers_and_counts_them(tmp_path):
    host, box, other = _pair(tmp_path, "host"), _pair(tmp_path, "box"), _pair(tmp_path, "other")
    context = zmq.Context()
    endpoint = f"tcp://127.0.0.1:{_free()}"
    pub = transport.publisher(context, endpoint, keys=keys.ServerKeys(box, frozenset([host.public])))
    allowed = transport.subscriber(context, [endpoint], keys=keys.ClientKeys(host, {endpoint: box.public}))
    refused = transport.subscriber(context, [endpoint], keys=keys.ClientKeys(other, {endpoint: box.public}))
    assert _received(allowed, pub) >= 10
    assert _received(refused, pub, n=1, polls=100) == 0
    deadline = time.monotonic() + 5
    while transport.refused(context) == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert transport.refused(context) >= 1
    for s in (allowed, refused, pub):
        s.close(linger=0)


def _free() -> int:
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _handshakes(socket: zmq.Socket, seconds: float, until=None) -> list[int]:
    """The handshake events (succeeded / failed) a socket's monitor reports within seconds."""
    from zmq.utils.monitor import recv_monitor_message
    wanted = (zmq.EVENT_HANDSHAKE_SUCCEEDED, zmq.EVENT_HANDSHAKE_FAILED_NO_DETAIL,
              zmq.EVENT_HANDSHAKE_FAILED_PROTOCOL, zmq.EVENT_HANDSHAKE_FAILED_AUTH)
    monitor, events = socket.get_monitor_socket(), []
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline and not (until and until(events)):
        if monitor.poll(50):
            event = recv_monitor_message(monitor)["event"]
            if event in wanted:
                events.append(event)
    socket.disable_monitor()
    monitor.close(linger=0)
    return events


def test_the_recorder_records_the_keyed_box_and_nothing_of_a_stranger(session, tmp_path):
    from mocap.recording import recorder
    keyed, host, box = _keyed(session, tmp_path)
    stranger = _pair(tmp_path, "stranger")
    recorded = {}
    for name, pair in (("box", box), ("stranger", stranger)):
        endpoint = f"tcp://127.0.0.1:{_free()}"  # the session expects the box's key there
        path = dataclasses.replace(keyed, inputs=[endpoint], curve=CurveSettings("host.key", {endpoint: box.public}))\
            .save(tmp_path / f"{name}.json")
        context = zmq.Context()
        pub = transport.publisher(context, endpoint, keys=keys.ServerKeys(pair, frozenset([host.public])))
        stop = threading.Event()

        def send():
            while not stop.is_set():
                pub.send_multipart(wire.encode(wire.KeypointFrame(camera_id="cam0", capture_time_ns=time.time_ns())))
                time.sleep(0.01)

        sender = threading.Thread(target=send)
        sender.start()
        counts = recorder.record([endpoint], tmp_path / f"{name}.mcap", seconds=1.5, session=path)
        stop.set()
        sender.join()
        pub.close(linger=0)
        recorded[name] = counts.recorded.get("/camera/cam0", 0)
    assert recorded["box"] >= 50 and recorded["stranger"] == 0, recorded


def test_the_live_calibrator_hears_and_publishes_with_the_sessions_keys(session, tmp_path):
    from mocap.calibration import live
    keyed, host, box = _keyed(session, tmp_path)
    box_ep, publish = (f"tcp://127.0.0.1:{_free()}" for _ in range(2))
    keyed = dataclasses.replace(keyed, inputs=[box_ep, publish],
                                curve=CurveSettings("host.key", {box_ep: box.public, publish: host.public}))
    path = keyed.save(tmp_path / "session.json")
    context = zmq.Context()
    pub = transport.publisher(context, box_ep, keys=keys.ServerKeys(box, frozenset([host.public])))
    calibrator = threading.Thread(target=live.follow, args=([box_ep], path, tmp_path / "out", publish),
                                  kwargs={"duration_s": 4.0})
    calibrator.start()
    # The box admits the calibrator (it holds the host's key)...
    assert zmq.EVENT_HANDSHAKE_SUCCEEDED in _handshakes(pub, 3.0, until=lambda e: e)
    # ...and the calibrator serves the host's key: mocapd's expectation on its endpoint.
    client = keys.ClientKeys(host, {publish: host.public})
    reader = transport.subscriber(context, [publish], keys=client)
    assert _handshakes(reader, 3.0, until=lambda e: e) == [zmq.EVENT_HANDSHAKE_SUCCEEDED]
    stranger_view = transport.subscriber(context, [publish], keys=keys.ClientKeys(host, {publish: box.public}))
    assert zmq.EVENT_HANDSHAKE_FAILED_NO_DETAIL in _handshakes(stranger_view, 3.0, until=lambda e: e)
    calibrator.join(timeout=30)
    for s in (pub, reader, stranger_view):
        s.close(linger=0)


def test_a_keyed_replay_is_read_only_by_a_subscriber_expecting_its_key(tmp_path):
    from mocap.recording import recorder, replay
    with recorder.Recorder(tmp_path / "take.mcap") as r:
        for i in range(50):
            r.write(wire.encode(wire.KeypointFrame(camera_id="cam0", frame_index=i, capture_time_ns=i)), i)
    pair, host, other = _pair(tmp_path, "replay"), _pair(tmp_path, "host"), _pair(tmp_path, "other")
    endpoint = f"tcp://127.0.0.1:{_free()}"
    context = zmq.Context()
    right = transport.subscriber(context, [endpoint], keys=keys.ClientKeys(host, {endpoint: pair.public}))
    wrong = transport.subscriber(context, [endpoint], keys=keys.ClientKeys(host, {endpoint: other.public}))
    sent = []
    player = threading.Thread(target=lambda: sent.append(replay.replay(
        tmp_path / "take.mcap", endpoint, speed=None, wait_for_subscribers=5.0, keys=keys.ServerKeys(pair))))
    player.start()
    got = {"right": [], "wrong": []}
    deadline = time.monotonic() + 10
    while len(got["right"]) < 50 and time.monotonic() < deadline:
        for name, sub in (("right", right), ("wrong", wrong)):
            if sub.poll(10):
                got[name].append(wire.decode(sub.recv_multipart()).frame_index)
    player.join(timeout=30)
    assert sent == [50] and got["right"] == list(range(50)) and got["wrong"] == []
    for s in (right, wrong):
        s.close(linger=0)
    context.term()


def test_a_calibrated_session_keeps_the_keys_and_a_recording_carries_none(session, tmp_path):
    from mocap.calibration.from_messages import Estimated, write_session
    from mocap.model.solver import layout_json
    from mocap.recording import reader, recorder
    keyed, host, box = _keyed(session, tmp_path)
    source = keyed.save(tmp_path / "session.json")
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / "coco17.json"), skeleton)
    imus = _core.load_imu_sites(str(paths.IMU_SETS["6"]), skeleton)
    estimated = Estimated(skeleton.to_json(), json.dumps(imu_set_json(skeleton, imus)),
                          json.dumps(layout_json(skeleton, layout)), {"frames": 1})
    write_session(tmp_path / "calibrated" / "here", source, estimated, {"frames": 1})
    calibrated = tmp_path / "calibrated" / "here" / "session.json"
    assert Session.load(calibrated).curve.host_key == "../../host.key"  # the one key file, not a copy
    assert Session.load(calibrated).client_keys().pair == host
    _core.HostPipeline.load(str(calibrated))  # mocapd reads the key from the new folder
    with recorder.Recorder(tmp_path / "take.mcap") as r:
        r.attach_session(source)
    (tmp_path / "attached").mkdir()
    attached = reader.read_session(tmp_path / "take.mcap", tmp_path / "attached")
    assert Session.load(attached).curve is None and "curve" not in attached.read_text()
    assert not list((tmp_path / "attached").glob("*.key"))
    _core.HostPipeline.load(str(attached))  # a recording is solved offline without keys
