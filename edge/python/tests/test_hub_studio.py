"""The simulated studio's IMUs through the real hub: simulated sensor nodes playing a stream
file, on a simulated bus (all at once) and served over TCP in socketcand's protocol to the hub
running as its own process (real time)."""

from __future__ import annotations

import signal
import socket
import struct
import subprocess
import sys
import threading
import time

import can
import numpy as np
import pytest
import zmq
from can.interfaces.socketcand import socketcand as python_can_socketcand
from mocap.net import transport, wire
from mocap_edge.errors import EdgeError
from mocap_edge.hub.config import HubConfig
from mocap_edge.hub.sim import socketcand
from mocap_edge.hub.sim.studio import StudioNodes, studio_batches, studio_config
from mocap_edge.streams import Streams

SENSORS = ["pelvis", "thigh_l", "foot_r"]
RATE = 100
Q_STEP, A_STEP = 2.0**-13, 2.0**-6  # the CAN database's resolutions (proto/can/README.md)


def make_streams(seconds: float = 3.0, seed: int = 0) -> Streams:
    """IMU-only streams: each sensor turning about its own axis, accelerations wandering."""
    rng = np.random.default_rng(seed)
    times = np.arange(0, int(seconds * RATE)) * (1_000_000_000 // RATE)
    t = times * 1e-9
    quats = np.zeros((len(t), len(SENSORS), 4))
    for k in range(len(SENSORS)):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        angle = (k + 1) * 1.3 * t
        quats[:, k, 0] = np.cos(angle / 2)
        quats[:, k, 1:] = np.sin(angle / 2)[:, None] * axis
    accs = rng.normal(0, 3, (len(t), len(SENSORS), 3)) + [0, 0, 9.81]
    return Streams(["cam0"], "blazepose33", np.array([[640, 480]]), np.zeros(0, np.int64),
                   np.zeros((0, 1, 33, 3), np.float32), np.zeros(0, bool), list(SENSORS), times, quats, accs)


def check_against_stream(streams: Streams, start_ns: int, samples: list, time_tolerance_ns: float,
                         sensors: list[str] = SENSORS) -> None:
    """Every stream sample of `sensors` exactly once, at its time, with its values within the
    wire format's quantisation."""
    assert {s.sensor_id for s in samples} == set(sensors)
    assert len(samples) == len(streams.imu_times_ns) * len(sensors)
    seen = set()
    for s in samples:
        k = SENSORS.index(s.sensor_id)
        i = int(round((s.sample_time_ns - start_ns) / (1e9 / RATE)))
        assert (s.sensor_id, i) not in seen
        seen.add((s.sensor_id, i))
        assert abs(s.sample_time_ns - start_ns - streams.imu_times_ns[i]) < time_tolerance_ns
        q = streams.imu_quaternions[i, k] * np.sign(streams.imu_quaternions[i, k, 0] or 1.0)
        assert np.abs(np.array([s.qw, s.qx, s.qy, s.qz]) - q).max() < 2 * Q_STEP
        assert np.abs(np.array([s.ax, s.ay, s.az]) - streams.imu_accelerations[i, k]).max() <= A_STEP / 2 + 1e-9


def test_the_studio_batches_are_the_stream_through_the_hubs_own_decoding_and_clock_fit():
    streams, start = make_streams(), 1_790_000_000_000_000_000
    batches = studio_batches(streams, start)
    check_against_stream(streams, start, [s for b in batches for s in b.samples], time_tolerance_ns=60_000)
    assert [b.sequence for b in batches] == list(range(len(batches)))
    for b in batches:  # each sample leaves in the batch after it reached the hub, within two periods
        assert all(0 < b.send_time_ns - s.sample_time_ns < 25_000_000 for s in b.samples)


def test_the_studio_configuration_round_trips_and_must_match_the_stream(tmp_path):
    streams = make_streams(1.0)
    config = studio_config(streams)
    (tmp_path / "hub.toml").write_text(config.to_toml())
    assert HubConfig.load(tmp_path / "hub.toml") == config and config.rate_hz == RATE
    with pytest.raises(EdgeError, match="rate"):
        StudioNodes(streams, HubConfig(config.names, rate_hz=60), 0, 0)
    with pytest.raises(EdgeError, match="wrist"):
        StudioNodes(streams, HubConfig({1: "wrist"}, rate_hz=RATE), 0, 0)


def test_socketcand_messages_are_the_ones_python_can_reads_and_writes():
    """Both directions against python-can's own socketcand converters."""
    message = python_can_socketcand.convert_ascii_message_to_can_message(
        socketcand.frame_message(0x1C5, bytes([0, 0x12, 0xAB, 0xFF]), 1_790_000_000_123_456_789).decode())
    assert (message.arbitration_id, bytes(message.data)) == (0x1C5, bytes([0, 0x12, 0xAB, 0xFF]))
    assert message.timestamp == pytest.approx(1_790_000_000.123456, abs=1e-6)
    sent = python_can_socketcand.convert_can_message_to_ascii_message(
        can.Message(arbitration_id=0x80, data=[7, 0xA0], is_extended_id=False))
    assert socketcand.parse_send(sent) == (0x80, bytes([7, 0xA0]))
    for bad in ("< send 80 >", "< send 80 2 01 >", "< send zz 1 01 >", "< send 800 1 01 >", "< frame 80 1 01 >",
                "< send 80 9 0 0 0 0 0 0 0 0 0 >"):
        assert socketcand.parse_send(bad) is None, bad


def run(cmd: list[str], **kw) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "mocap_edge", *cmd], **kw)


def stop(process: subprocess.Popen) -> str:
    if process.poll() is None:
        process.send_signal(signal.SIGTERM)
    try:
        return process.communicate(timeout=10)[1] or ""
    finally:
        if process.poll() is None:
            process.kill()


def test_the_hub_process_reads_simulated_nodes_served_over_socketcand(tmp_path):
    """Real time, two processes: the nodes (one unplugged for 2.4 s) served over TCP, the hub
    reading them with python-can's socketcand interface and publishing on ZeroMQ."""
    streams = make_streams(4.0)
    streams.save(tmp_path / "streams.npz")
    (tmp_path / "hub.toml").write_text(studio_config(streams).to_toml())
    start = time.time_ns() + 2_500_000_000
    nodes = run(["sim-nodes", "--streams", str(tmp_path / "streams.npz"), "--config", str(tmp_path / "hub.toml"),
                 "--port", "0", "--start-ns", str(start), "--stop", "0.8", "3.2", "--stop-sensor", "thigh_l"],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    hub = None
    sub = transport.subscriber(zmq.Context.instance(), [endpoint := f"tcp://127.0.0.1:{free_port()}"])
    try:
        port = nodes.stdout.readline().split()[1]
        hub = run(["imu-hub", "--can", f"socketcand:127.0.0.1:{port}:can0", "--config", str(tmp_path / "hub.toml"),
                   "--bind", endpoint], stderr=subprocess.PIPE, text=True)
        batches, healths = [], []
        while time.time_ns() < start + 5_800_000_000:
            if sub.poll(100):
                message = wire.decode(sub.recv_multipart())
                (batches if isinstance(message, wire.ImuBatch) else healths).append((time.time_ns(), message))
    finally:
        sub.close(0)
        hub_log = stop(hub) if hub else ""
        nodes_log = stop(nodes)
    assert "Traceback" not in hub_log + nodes_log, hub_log + nodes_log
    samples = [s for _, b in batches for s in b.samples]
    # the loopback's delay before a Sync reaches the nodes biases every time alike: well under 1 ms
    check_against_stream(streams, start, [s for s in samples if s.sensor_id != "thigh_l"], 1_000_000,
                         ["pelvis", "foot_r"])
    gap = np.array([s.sample_time_ns - start for s in samples if s.sensor_id == "thigh_l"]) * 1e-9
    assert not ((gap > 0.81) & (gap < 3.19)).any() and (gap > 3.3).any() and (gap < 0.7).any()
    # stale from 1 s of silence (hub.toml's stale_s) until it is back: a Health report (one a
    # second) falls in those 1.4 s
    thigh = [next(s for s in h.streams if s.stream == "imu/thigh_l") for _, h in healths]
    assert any(not s.active for s in thigh) and thigh[-1].active
    assert thigh[-1].lost == pytest.approx(2.4 * RATE, abs=2)  # its counter ran on: those samples lost


def test_garbage_from_a_client_is_counted_and_the_server_goes_on():
    """Bad messages are counted; a client that resets before the greeting does not stop the server."""
    streams = make_streams(1.0)
    nodes = StudioNodes(streams, studio_config(streams), time.time_ns(), time.time_ns())
    with socketcand.listen(0) as listener:
        server = socketcand.Server(nodes, listener)
        gone = socket.create_connection(listener.getsockname())  # a client that resets at once (a port probe)
        gone.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        gone.close()
        with socket.create_connection(listener.getsockname(), timeout=5.0) as client:
            done: list[bool] = []
            thread = threading.Thread(target=server.run, args=(lambda: bool(done),))
            thread.start()
            try:
                assert client.recv(64) == b"< hi >"
                client.sendall(b"< bogus >< open can0 >")
                assert client.recv(64) == b"< ok >"
                client.sendall(b"< rawmode >")
                assert client.recv(64) == b"< ok >"
                client.sendall(b"< send 80 1 zz >" + b"x" * 500 + b"< send 80 1 05 >")
                deadline = time.monotonic() + 5
                received = b""
                while b"< frame" not in received and time.monotonic() < deadline:
                    received += client.recv(4096)
            finally:
                done.append(True)
                thread.join(timeout=5)
    assert b"< frame" in received  # SyncReports answering the good Sync
    assert server.counts.malformed == 2 and server.counts.frames_received == 1


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_the_hub_opens_its_link_again_when_the_server_goes_away():
    """A socketcand server that stops (its box rebooted, the cable pulled) closes the hub's TCP
    link; python-can's client then reads nothing forever without an error. The hub counts the
    link lost, tries to open it again once a second, and picks the nodes up again."""
    from mocap_edge.hub.can_bus import open_bus
    from mocap_edge.hub.hub import Hub
    from mocap_edge.hub.service import HubService

    streams = make_streams(6.0)
    config = studio_config(streams)
    nodes = StudioNodes(streams, config, time.time_ns() + 500_000_000, time.time_ns())
    with socketcand.listen(0) as listener:
        uri = f"socketcand:127.0.0.1:{listener.getsockname()[1]}:can0"
        stopped: list[bool] = []
        first = threading.Thread(target=socketcand.Server(nodes, listener).run, args=(lambda: bool(stopped),))
        first.start()
        published: list = []
        service = HubService(open_bus(uri), Hub(config), published.append, reopen=lambda: open_bus(uri))
        hub = threading.Thread(target=service.run, args=(lambda: False, 6.0))
        hub.start()
        time.sleep(1.5)
        stopped.append(True)  # the server goes away, its client's socket closed
        first.join(timeout=5)
        time.sleep(1.0)
        again: list[bool] = []
        second = threading.Thread(target=socketcand.Server(nodes, listener).run, args=(lambda: bool(again),))
        second.start()  # back, on the same port
        hub.join(timeout=20)
        again.append(True)
        second.join(timeout=5)
    assert service.bus_errors.counts["link_lost"] >= 1 and service.port is not None
    times = np.array([s.sample_time_ns for m in published if isinstance(m, wire.ImuBatch) for s in m.samples
                      if s.sensor_id == "pelvis"])
    gaps = np.diff(times) * 1e-9
    assert gaps.max() > 0.8 and (times > times[0] + 3.0e9).any()  # a hole while it was away, samples after
    service.port.bus.shutdown()
