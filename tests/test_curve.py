"""Authenticated streams across processes (README, "Securing the streams"; docs/security.md).

mocapd with a session that lists CURVE keys: a stranger publishing on an input's endpoint with a
key the session does not expect is refused — none of its frames reaches the host — and counted in
Health ("link/<endpoint>", handshake_failures) and in mocapd's exit line, while the real camera
box (`python -m mocap_edge camera`, its secret key and the host's key admitted) on another input
is heard; mocapd's output is read with the host's key, by the admitted subscribers only. A session without keys whose inputs leave
the machine is refused unless --insecure."""
# Every endpoint here is on loopback: nothing leaves this machine.

import dataclasses
import json
import re
import subprocess
import sys
import threading
import time

import pytest
import zmq

from mocap import _core, paths
from mocap.demo import play
from mocap.demo.studio import free_ports
from mocap.io.session import CurveSettings, Session
from mocap.model import studio
from mocap.model.solver import imu_set_json
from mocap.net import keys, transport, wire

pytestmark = pytest.mark.skipif(not play.MOCAPD.exists(), reason="mocapd is not built (make build)")


def _session(folder, inputs, output) -> Session:
    (folder / "rig.json").write_text(studio.ring_rig(2).to_json())
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    imus = _core.load_imu_sites(str(paths.IMU_SETS["13"]), skeleton)
    (folder / "imus.json").write_text(json.dumps(imu_set_json(skeleton, imus)))
    return Session(str(paths.DEFAULT_SKELETON), "rig.json", str(paths.LAYOUTS / "blazepose33.json"), "imus.json",
                   inputs, output, base=folder)


def _stranger(endpoint: str, pair: keys.KeyPair, stop: threading.Event) -> None:
    """Publishes cam0's frames on endpoint with a key the session does not expect there."""
    context = zmq.Context()
    with transport.publisher(context, endpoint, keys=keys.ServerKeys(pair)) as pub:
        index = 0
        while not stop.is_set():
            frame = wire.KeypointFrame(camera_id="cam0", frame_index=index, capture_time_ns=time.time_ns(),
                                       keypoint_layout="blazepose33", detected=True)
            pub.send_multipart(wire.encode(frame))
            index += 1
            time.sleep(1 / 60)
    context.term()


def _healths(output: str, client: keys.ClientKeys, host: subprocess.Popen) -> list:
    sub = transport.subscriber(zmq.Context.instance(), [output], keys=client)
    healths = []
    while host.poll() is None:
        if sub.poll(200):
            msg = wire.decode(sub.recv_multipart())
            if isinstance(msg, wire.Health):
                healths.append(msg)
    sub.close()
    return healths


def test_a_stranger_is_refused_and_counted_while_the_real_box_is_heard(tmp_path):
    for name in ("host", "cam1", "stranger"):
        keys.make_keypair(tmp_path / "keys", name)
    pair = {n: keys.read_secret(tmp_path / "keys" / f"{n}.key") for n in ("host", "cam1", "stranger")}
    stranger_ep, box_ep, output = (f"tcp://127.0.0.1:{p}" for p in free_ports(3))
    session = dataclasses.replace(_session(tmp_path, [stranger_ep, box_ep], output), curve=CurveSettings(
        "keys/host.key", {stranger_ep: pair["cam1"].public, box_ep: pair["cam1"].public}))
    # The stranger sits on an input whose expected key is cam1's (say, the box's address taken over).
    path = session.save(tmp_path / "session.json")
    stop = threading.Event()
    stranger = threading.Thread(target=_stranger, args=(stranger_ep, pair["stranger"], stop))
    stranger.start()
    host = subprocess.Popen([str(play.MOCAPD), str(path), "--duration", "8", "--health-period", "0.5", "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    box = subprocess.Popen([sys.executable, "-m", "mocap_edge", "camera", "--source", "fake:", "--model", "fake:",
                            "--camera", "cam1", "--bind", box_ep, "--realtime", "--start-ns",
                            str(time.time_ns() + 4_000_000_000), "--curve-secret", str(tmp_path / "keys/cam1.key"),
                            "--curve-allow", str(tmp_path / "keys/host.pub")], stderr=subprocess.PIPE, text=True)
    # A reader with a key the box does not admit, though it knows the box's public key.
    other = keys.KeyPair(*(k.decode() for k in zmq.curve_keypair()))
    snoop = transport.subscriber(zmq.Context.instance(), [box_ep], keys=keys.ClientKeys(other, {box_ep: pair["cam1"].public}))
    try:
        healths = _healths(output, Session.load(path).client_keys(), host)
        out, err = host.communicate(timeout=30)
    finally:
        stop.set()
        stranger.join(timeout=10)
        box.wait(timeout=30)
        snooped = snoop.poll(0)
        snoop.close(linger=0)
    assert host.returncode == 0, err[-2000:]
    assert "streams authenticated and encrypted (CURVE)" in err
    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["refused"][stranger_ep] >= 2 and summary["refused"][box_ep] == 0, summary
    assert f"refused a publisher on {stranger_ep}" in err
    assert box.returncode == 0 and "cam1: 60 frames sent" in (box_log := box.stderr.read())
    # The box served mocapd (the host's key admitted) and refused the other reader, which got nothing.
    assert re.search(r"; [1-9]\d* subscribers refused", box_log) and not snooped, box_log
    assert len(healths) >= 10  # the output was read with the host's keys
    streams = {s.stream: s for s in healths[-1].streams}
    assert streams["camera/cam0"].received == 0  # none of the stranger's frames reached the host
    assert streams["camera/cam1"].received >= 55, streams["camera/cam1"]
    assert streams[f"link/{stranger_ep}"].handshake_failures == summary["refused"][stranger_ep]
    assert not any(s.active for h in healths for s in h.streams if s.stream == f"link/{stranger_ep}")
    assert any(s.active for h in healths for s in h.streams if s.stream == f"link/{box_ep}")
    assert streams[f"link/{box_ep}"].handshake_failures == 0


def test_mocapds_output_is_read_with_the_hosts_key_by_the_admitted_subscribers_only(tmp_path):
    keys.make_keypair(tmp_path / "keys", "host")
    host_pair = keys.read_secret(tmp_path / "keys" / "host.key")
    admitted, other = (keys.KeyPair(*(k.decode() for k in zmq.curve_keypair())) for _ in range(2))
    box_ep, output = (f"tcp://127.0.0.1:{p}" for p in free_ports(2))
    session = dataclasses.replace(_session(tmp_path, [box_ep], output), curve=CurveSettings(
        "keys/host.key", {box_ep: other.public}, subscribers=[admitted.public]))
    host = subprocess.Popen([str(play.MOCAPD), str(session.save(tmp_path / "s.json")), "--duration", "4",
                             "--health-period", "0.2", "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    got = {}

    def read(name, client):
        got[name] = _healths(output, client, host)

    readers = [threading.Thread(target=read, args=args) for args in (
        ("admitted", keys.ClientKeys(admitted, {}, default=host_pair.public)),
        ("not admitted", keys.ClientKeys(other, {}, default=host_pair.public)),
        ("wrong server key", keys.ClientKeys(admitted, {}, default=other.public)))]
    for r in readers:
        r.start()
    out, _ = host.communicate(timeout=30)
    for r in readers:
        r.join(timeout=10)
    assert host.returncode == 0 and len(got["admitted"]) >= 5, got
    assert got["not admitted"] == [] and got["wrong server key"] == []
    assert json.loads(out.decode().strip().splitlines()[-1])["subscribers_refused"] >= 1


def test_inputs_off_this_machine_need_keys_or_insecure(tmp_path):
    # 0.0.0.0 is not a loopback address to mocapd's check, though Linux connects it to this machine:
    # the test sends nothing off it.
    box, output = (f"tcp://{a}:{p}" for a, p in zip(("0.0.0.0", "127.0.0.1"), free_ports(2)))
    session = _session(tmp_path, [box], output)
    path = session.save(tmp_path / "session.json")
    refused = subprocess.run([str(play.MOCAPD), str(path), "--duration", "0.2"], capture_output=True, text=True,
                             timeout=30)
    assert refused.returncode == 1 and "no \"curve\" keys" in refused.stderr, refused.stderr
    allowed = subprocess.run([str(play.MOCAPD), str(path), "--duration", "0.2", "--insecure", "--quiet"],
                             capture_output=True, text=True, timeout=30)
    assert allowed.returncode == 0 and f"WARNING: --insecure: input {box}" in allowed.stderr


def test_the_simulated_studio_with_keys_is_solved_and_recorded_as_without(tmp_path):
    from mocap.demo import score, studio as live_studio
    from mocap.recording import reader

    # Three cameras: a dozen processes starting at once on a shared machine come up too late for a short take.
    keyed = live_studio.prepare(tmp_path / "studio", seconds=3.0, cameras=3, seed=4, curve=True)
    assert Session.load(keyed.session).curve is not None
    run = play.play(keyed, record=tmp_path / "take.mcap")
    result = score.score(keyed, run)
    assert result["dropped"] == 0 and len(run.poses) == 180, result  # every frame of 3 s at 60 fps
    links = [s for s in run.healths[-1].streams if s.stream.startswith("link/")]
    assert len(links) == 4 and all(s.handshake_failures == 0 for s in links), links
    # Each input's link was up (the boxes have closed theirs by mocapd's last Health).
    up = {s.stream for h in run.healths for s in h.streams if s.stream.startswith("link/") and s.active}
    assert up == {s.stream for s in links}, up
    assert sum(run.host_summary["refused"].values()) == 0
    with reader.Recording(tmp_path / "take.mcap") as recording:  # the recorder heard every box and mocapd
        topics = {m.topic for m in recording.messages()}
    assert {*(f"/camera/{c}" for c in keyed.camera_ids), "/imu/hub0", "/pose"} <= topics, topics
