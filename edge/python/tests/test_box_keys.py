"""The edge boxes with CURVE keys (README, "Securing the streams"): a box given its secret key
publishes only to subscribers that expect its public key (and, with --curve-allow, hold an admitted
key); a bad key file stops it with what is wrong before it publishes anything."""

import os
import subprocess
import sys
import time

import zmq

from mocap.net import keys, transport, wire
from mocap_edge.hub.service import publisher


def _free_endpoint() -> str:
    with zmq.Context.instance().socket(zmq.PUB) as probe:
        return f"tcp://127.0.0.1:{probe.bind_to_random_port('tcp://127.0.0.1')}"


def _box(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mocap_edge", *args], capture_output=True, text=True, timeout=60)


def test_a_box_with_a_bad_key_file_says_what_is_wrong(tmp_path):
    keys.make_keypair(tmp_path, "cam0")
    os.chmod(tmp_path / "cam0.key", 0o644)
    camera = ["camera", "--source", "fake:", "--model", "fake:", "--bind", _free_endpoint()]
    out = _box(*camera, "--curve-secret", str(tmp_path / "cam0.key"))
    assert out.returncode == 1 and "readable by others (mode 0644): chmod 600" in out.stderr, out.stderr
    out = _box(*camera, "--curve-secret", str(tmp_path / "none.key"))
    assert out.returncode == 1 and "cannot read secret key" in out.stderr, out.stderr
    os.chmod(tmp_path / "cam0.key", 0o600)
    out = _box(*camera, "--curve-secret", str(tmp_path / "cam0.key"), "--curve-allow", "notakey")
    assert out.returncode == 1 and "'notakey' is neither a public key" in out.stderr, out.stderr
    out = _box(*camera, "--curve-allow", str(tmp_path / "cam0.pub"))
    assert out.returncode == 1 and "--curve-allow needs --curve-secret" in out.stderr, out.stderr
    hub = _box("imu-hub", "--config", str(tmp_path / "hub.toml"), "--bind", _free_endpoint(), "--curve-secret",
               str(tmp_path / "none.key"))
    assert hub.returncode == 1 and "cannot read secret key" in hub.stderr, hub.stderr


def test_the_hubs_keyed_stream_reaches_the_admitted_host_only(tmp_path):
    for name in ("hub0", "host", "other"):
        keys.make_keypair(tmp_path, name)
    hub, host, other = (keys.read_secret(tmp_path / f"{n}.key") for n in ("hub0", "host", "other"))
    endpoint = _free_endpoint()
    publish, socket = publisher(endpoint, keys.ServerKeys(hub, frozenset([host.public])))
    context = zmq.Context()
    readers = {"host": transport.subscriber(context, [endpoint], keys=keys.ClientKeys(host, {endpoint: hub.public})),
               "other": transport.subscriber(context, [endpoint], keys=keys.ClientKeys(other, {endpoint: hub.public})),
               "plain": transport.subscriber(context, [endpoint])}
    got = dict.fromkeys(readers, 0)
    deadline = time.monotonic() + 5
    while got["host"] < 20 and time.monotonic() < deadline:
        publish(wire.ImuBatch(hub_id="hub0", sequence=1))
        time.sleep(0.01)
        for name, sub in readers.items():
            while sub.poll(0):
                assert wire.decode(sub.recv_multipart()).hub_id == "hub0"
                got[name] += 1
    assert got["host"] >= 20 and got["other"] == 0 and got["plain"] == 0, got
    for sub in readers.values():
        sub.close(linger=0)
    socket.close(linger=0)
    context.term()
