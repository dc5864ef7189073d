"""systemd's service notifications from the boxes (mocap_edge.supervisor), received on a real
Unix datagram socket as systemd's NOTIFY_SOCKET would."""

from __future__ import annotations

import os
import socket
import subprocess
import sys

import pytest

from mocap_edge.supervisor import Supervisor


@pytest.fixture
def notify_socket(tmp_path):
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(str(tmp_path / "notify"))
    sock.settimeout(5.0)
    yield sock, str(tmp_path / "notify")
    sock.close()


def received(sock: socket.socket) -> list[str]:
    out = []
    sock.settimeout(0.2)
    try:
        while True:
            out.append(sock.recv(4096).decode())
    except TimeoutError:
        return out


def test_ready_once_then_the_watchdog_at_half_its_period(notify_socket):
    sock, path = notify_socket
    now = [0.0]
    supervisor = Supervisor({"NOTIFY_SOCKET": path, "WATCHDOG_USEC": "2000000"}, clock=lambda: now[0])
    for t in (0.0, 0.5, 0.99, 1.0, 1.5, 2.2, 2.3):
        now[0] = t
        supervisor.turn()
    supervisor.close()
    assert received(sock) == ["READY=1", "WATCHDOG=1", "WATCHDOG=1", "WATCHDOG=1", "STOPPING=1"]  # at 0, 1.0, 2.2


def test_no_watchdog_for_another_process_and_nothing_without_systemd(notify_socket):
    sock, path = notify_socket
    other = Supervisor({"NOTIFY_SOCKET": path, "WATCHDOG_USEC": "1000", "WATCHDOG_PID": str(os.getpid() + 1)})
    other.turn()
    other.turn()
    assert received(sock) == ["READY=1"]
    outside = Supervisor({})
    outside.turn()
    outside.close()
    assert received(sock) == [] and outside.failed == 0


def test_a_supervisor_gone_is_counted_and_the_box_carries_on(notify_socket, tmp_path, caplog):
    sock, path = notify_socket
    supervisor = Supervisor({"NOTIFY_SOCKET": path, "WATCHDOG_USEC": "1"})
    supervisor.turn()
    sock.close()
    os.unlink(path)
    for _ in range(3):
        supervisor.turn()
    assert supervisor.failed == 3 and len([r for r in caplog.records if "not sent" in r.message]) == 1


def test_the_abstract_namespace_is_addressed(tmp_path):
    name = f"mocap-test-{os.getpid()}"
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind("\0" + name)
    try:
        Supervisor({"NOTIFY_SOCKET": "@" + name}).turn()
        sock.settimeout(5.0)
        assert sock.recv(64) == b"READY=1"
    finally:
        sock.close()


def test_a_camera_box_notifies_ready_then_feeds_the_watchdog_per_frame(notify_socket):
    sock, path = notify_socket
    env = {**os.environ, "NOTIFY_SOCKET": path, "WATCHDOG_USEC": "100000"}  # a watchdog every 50 ms
    box = subprocess.Popen([sys.executable, "-m", "mocap_edge", "camera", "--source", "fake:", "--model", "fake:",
                            "--bind", "tcp://127.0.0.1:0", "--realtime"], env=env, stderr=subprocess.PIPE, text=True)
    states = []
    try:
        while box.poll() is None:  # read as systemd does, while the box runs
            states += received(sock)
        states += received(sock)
    finally:
        box.kill()
        box.wait()
    assert box.returncode == 0, box.stderr.read()
    box.stderr.close()
    assert states[0] == "READY=1" and states[-1] == "STOPPING=1"
    assert 10 <= states.count("WATCHDOG=1") <= 21  # 60 frames over 1 s


def test_a_supervisor_that_does_not_read_never_blocks_the_box(notify_socket):
    sock, path = notify_socket  # never read: its queue fills after a few datagrams
    supervisor = Supervisor({"NOTIFY_SOCKET": path, "WATCHDOG_USEC": "1"})
    for _ in range(1000):
        supervisor.turn()
    assert supervisor.failed > 0
