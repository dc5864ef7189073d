"""Helpers of the in-VM tests (tests/vm/stage2.sh has set the devices up: vcan0, i2c-stub at
the hub-local IMU's address on /dev/i2c-0, the gpio-sim chip `cam-trigger` with its line
`trigger`, vimc). Python under TCG is slow: each test imports only what it uses."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
START_S = 60.0  # bound on a hub process's start under TCG (its imports take ~10 s; the machine is shared)


def sh(*command: str, check: bool = True) -> subprocess.CompletedProcess:
    """A tool of the host's tree (ip, cansend, i2cset, ...); its output in the failure."""
    done = subprocess.run(command, capture_output=True, text=True, timeout=60)
    if check and done.returncode != 0:
        pytest.fail(f"{' '.join(command)} failed ({done.returncode}): {done.stdout}{done.stderr}")
    return done


def mocap_edge(*args: str) -> subprocess.Popen:
    """`python -m mocap_edge ARGS`, its stderr captured."""
    return subprocess.Popen([sys.executable, "-m", "mocap_edge", *args], cwd=REPO, stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def stop(process: subprocess.Popen, timeout_s: float = 30.0) -> str:
    """SIGTERM, then its stderr (killed if it does not end)."""
    if process.poll() is None:
        process.send_signal(signal.SIGTERM)
    try:
        _, err = process.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        process.kill()
        _, err = process.communicate()
        err += f"\n(did not end {timeout_s} s after SIGTERM: killed)"
    return err


class Messages:
    """What a ZeroMQ subscriber received from a box, decoded (mocap.net.wire)."""

    def __init__(self, endpoint: str):
        import zmq

        from mocap.net import transport, wire

        self._wire = wire
        self.socket = transport.subscriber(zmq.Context.instance(), [endpoint])
        self.got: list = []

    def until(self, done, timeout_s: float, process: subprocess.Popen | None = None) -> bool:
        """Receives until done(self.got) is true (True) or timeout_s passed or process ended (False)."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and (process is None or process.poll() is None):
            if self.socket.poll(100):
                self.got.append(self._wire.decode(self.socket.recv_multipart()))
                if done(self.got):
                    return True
        return False

    def close(self) -> None:
        self.socket.close(0)
