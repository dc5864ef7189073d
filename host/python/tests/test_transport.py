"""The system's ZeroMQ subscribers (mocap.net.transport) against a publisher that hangs: its
TCP connection stays open, so only the heartbeat finds it out; the subscriber then connects
anew and hears the publisher again once it runs."""

import signal
import subprocess
import sys
import time

import zmq
from zmq.utils.monitor import recv_monitor_message

from mocap.net import transport

PUBLISHER = """
import sys, time, zmq
pub = zmq.Context().socket(zmq.PUB)
port = pub.bind_to_random_port("tcp://127.0.0.1")
print(port, flush=True)
while True:
    pub.send(b"x")
    time.sleep(0.005)
"""


def receive(sub: zmq.Socket, monitor: zmq.Socket, count: int, timeout_s: float = 30.0) -> tuple[int, list[int]]:
    """Messages received (up to count) and the monitor's events, within timeout_s."""
    received, events, deadline = 0, [], time.monotonic() + timeout_s
    poller = zmq.Poller()
    poller.register(sub, zmq.POLLIN)
    poller.register(monitor, zmq.POLLIN)
    while received < count and time.monotonic() < deadline:
        for socket, _ in poller.poll(50):
            if socket is sub:
                sub.recv()
                received += 1
            else:
                events.append(recv_monitor_message(monitor)["event"])
    return received, events


def test_a_hung_publisher_is_dropped_by_the_heartbeat_and_heard_again_when_it_runs():
    box = subprocess.Popen([sys.executable, "-c", PUBLISHER], stdout=subprocess.PIPE, text=True)
    context = zmq.Context()
    try:
        port = int(box.stdout.readline())
        sub = transport.subscriber(context, [f"tcp://127.0.0.1:{port}"])
        monitor = sub.get_monitor_socket(zmq.EVENT_DISCONNECTED | zmq.EVENT_HANDSHAKE_SUCCEEDED)
        assert receive(sub, monitor, 10)[0] == 10
        box.send_signal(signal.SIGSTOP)  # hung: the connection stays open, nothing answers
        stopped = time.monotonic()
        events: list[int] = []
        while zmq.EVENT_DISCONNECTED not in events and time.monotonic() - stopped < 30:
            events += receive(sub, monitor, 1 << 30, timeout_s=0.2)[1]
        assert zmq.EVENT_DISCONNECTED in events, "the hung publisher's connection was never dropped"
        assert time.monotonic() - stopped >= 0.5 * transport.HEARTBEAT_MS[1] / 1000  # by the heartbeat
        box.send_signal(signal.SIGCONT)
        assert receive(sub, monitor, 10)[0] == 10  # connected anew
    finally:
        box.kill()
        box.wait()
        context.destroy(linger=0)
