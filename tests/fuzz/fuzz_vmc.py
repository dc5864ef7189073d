"""atheris target: the VMC (OSC over UDP) sender's inputs (mocap.net.vmc): any pose vector of the
default skeleton and any time, as the live solve hands them over. Input: 67 doubles (theta,
then the time), little-endian. Allowed failure: none, send returns False and counts a frame
it cannot send (skipped); a frame it sends is a well-formed OSC bundle."""

import struct

import atheris
import numpy as np

with atheris.instrument_imports(include=["mocap.net"]):
    from mocap import _core, paths
    from mocap.net import vmc

import _harness  # noqa: E402

SKELETON = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
SENDER = vmc.VmcSender(SKELETON, "127.0.0.1", 9)  # the discard port of loopback
N = SKELETON.pose_dim


def check(data: bytes) -> None:
    data = bytes(data[: 8 * (N + 1)]).ljust(8 * (N + 1), b"\0")
    values = struct.unpack(f"<{N + 1}d", data)
    theta, time_s = np.array(values[:N]), values[N]
    skipped, failures = SENDER.skipped, SENDER.failures
    sent = SENDER.send(theta, time_s)
    assert sent or SENDER.skipped + SENDER.failures == skipped + failures + 1
    if sent:
        packet = SENDER.encode(theta, time_s)
        assert packet.startswith(b"#bundle\0") and len(packet) % 4 == 0


if __name__ == "__main__":
    _harness.main(check, ())
