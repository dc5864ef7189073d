"""Simulated sensor nodes on a real python-can bus, in real time (a thread): each answers the
hub's Syncs and Commands, sends a heartbeat every second and, while running, its samples at
its rate — what the firmware's nodes do, for the hub's end-to-end tests (`virtual:` buses are
in-process: the runner and the hub share the process).

    python -m mocap_edge.hub.sim.runner --can URI --nodes 3,7 [--seed N]

runs still nodes, idle until a hub starts them, on any bus `--can` names (as the hub's:
socketcan:vcan0, slcan:...), until SIGINT or SIGTERM; it prints `running` once they listen, and
each node's state at the end.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time

import can
import numpy as np

from mocap_edge.errors import EdgeError
from mocap_edge.hub.can_bus import open_bus
from mocap_edge.hub.sim.bus import Motion, make_nodes, still
from mocap_edge.hub.sim.node import SimulatedNode


class NodeRunner(threading.Thread):
    """The nodes on `bus`, which must not hand back the frames it sends (open_bus(uri,
    own_messages=False)): every frame it receives is another's (python-can's is_rx cannot
    tell: frames from this machine, SocketCAN's vcan, read as not received)."""

    def __init__(self, bus: can.BusABC, nodes: dict[int, SimulatedNode], motion: Motion, clock_ns=time.time_ns):
        super().__init__(daemon=True, name="sim-nodes")
        self.bus, self.nodes, self.motion, self.clock_ns = bus, nodes, motion, clock_ns
        self.stopping = threading.Event()
        self.start_ns = clock_ns()
        self._next_sample = {i: self.start_ns for i in nodes}
        self._next_heartbeat = self.start_ns

    def run(self) -> None:
        while not self.stopping.is_set():
            message = self._recv(0.001)
            while message is not None:  # every frame waiting
                if not message.is_error_frame:
                    # stamped when it reached the bus, as a node's CAN controller stamps it
                    now = int(round(message.timestamp * 1e9)) if message.timestamp else self.clock_ns()
                    for node in self.nodes.values():
                        for frame in node.on_frame(message.arbitration_id, bytes(message.data), now):
                            self._send(frame)
                message = self._recv(0.0)
            now = self.clock_ns()
            self._samples(now)
            if now >= self._next_heartbeat:
                for node in self.nodes.values():
                    self._send(node.heartbeat(now))
                self._next_heartbeat += 1_000_000_000

    def _recv(self, timeout_s: float) -> can.Message | None:
        """The next frame, or None; a bus that fails (its interface down) is waited out."""
        try:
            return self.bus.recv(timeout=timeout_s)
        except can.CanOperationError:
            time.sleep(0.05)
            return None

    def stop(self) -> None:
        self.stopping.set()
        self.join(timeout=2.0)

    def _samples(self, now: int) -> None:
        for i, node in self.nodes.items():
            period = int(1e9 / node.rate_hz)
            while self._next_sample[i] <= now:
                t = self._next_sample[i]
                if node.running:
                    q, a = self.motion(i, (t - self.start_ns) * 1e-9)
                    for frame in node.sample(t, np.asarray(q), np.asarray(a)):
                        self._send(frame)
                self._next_sample[i] += period

    def _send(self, frame: tuple[int, bytes]) -> None:
        try:
            self.bus.send(can.Message(arbitration_id=frame[0], data=frame[1], is_extended_id=False))
        except can.CanError:
            pass  # a full or broken bus: the frame is lost, as on a real one



def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m mocap_edge.hub.sim.runner", description=__doc__.split("\n\n")[0])
    p.add_argument("--can", required=True, help="the bus: socketcan:IFACE, slcan:..., as the hub's --can")
    p.add_argument("--nodes", required=True, help="node ids 1..63, comma-separated, e.g. 3,7")
    p.add_argument("--seed", type=int, default=0, help="seed of the nodes' clock errors")
    a = p.parse_args(argv)
    try:
        ids = [int(i) for i in a.nodes.split(",")]
        if not all(1 <= i <= 63 for i in ids):
            raise ValueError
    except ValueError:
        p.error(f"--nodes {a.nodes!r}: node ids 1..63, comma-separated")
    try:
        port = open_bus(a.can, own_messages=False)
    except EdgeError as e:
        print(f"sim nodes: {e}", file=sys.stderr)
        return 1
    nodes = make_nodes(ids, np.random.default_rng(a.seed), origin_ns=time.time_ns(), running=False)
    stopping = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stopping.set())
    runner = NodeRunner(port.bus, nodes, still)
    runner.start()
    print("running", flush=True)
    while not stopping.wait(0.5):
        pass
    runner.stop()
    port.bus.shutdown()
    print("sim nodes: " + "; ".join(f"node {i} {n.state} at {n.rate_hz} Hz" for i, n in sorted(nodes.items())),
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
