"""SocketCAN: the IMU hub (`python -m mocap_edge imu-hub --can socketcan:vcan0`) and simulated
sensor nodes (`python -m mocap_edge.hub.sim.runner --can socketcan:vcan0`), two processes on
the kernel's vcan0. The hub discovers and configures the nodes, decodes their
frames and publishes ImuBatch; garbage frames sent with can-utils are counted by reason; the
interface taken down and up again is counted and logged, and the hub goes on. The tests run in
order on one hub and one set of nodes (each process starts in ~10 s under TCG)."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
import time

import pytest
from conftest import REPO, START_S, Messages, mocap_edge, sh, stop

NAMES = {3: "pelvis", 7: "forearm_l"}
ENDPOINT = "ipc:///tmp/vm-can-hub"
GARBAGE = [("cansend", "vcan0", "7E5#DEADBEEF"),  # no message at that id
           ("cangen", "vcan0", "-I", "7E5", "-L", "4", "-n", "20", "-g", "2"),
           ("cansend", "vcan0", "12345678#00"),  # an extended id
           ("cansend", "vcan0", "103#R"),  # a remote frame at node 3's ImuQuat
           ("cansend", "vcan0", "103#0102")]  # node 3's ImuQuat, 2 bytes of 8
UNKNOWN_IDS, BAD_LENGTHS = 23, 1


@pytest.fixture(scope="module")
def studio(tmp_path_factory):
    """The simulated nodes (a process: idle until the hub starts them), the hub, a subscriber."""
    config = tmp_path_factory.mktemp("can") / "hub.toml"
    config.write_text("[hub]\nrate_hz = 30\nsync_hz = 20\n\n[nodes]\n"
                      + "".join(f'{i} = "{name}"\n' for i, name in NAMES.items()))
    nodes = subprocess.Popen([sys.executable, "-m", "mocap_edge.hub.sim.runner", "--can", "socketcan:vcan0",
                              "--nodes", ",".join(map(str, NAMES))], cwd=REPO, stdin=subprocess.DEVNULL,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    messages = Messages(ENDPOINT)
    hub = mocap_edge("imu-hub", "--can", "socketcan:vcan0", "--config", str(config), "--bind", ENDPOINT)
    started: list[bool] = []  # the first test appends once the hub publishes: the others need it
    yield hub, messages, nodes, started
    stop(hub)
    stop(nodes)
    messages.close()


def batches_of(got, names=tuple(NAMES.values()), after_ns: int = 0) -> bool:
    """Every named sensor has a sample taken after after_ns in the ImuBatches received."""
    seen = {s.sensor_id for m in got if type(m).__name__ == "ImuBatch" for s in m.samples if s.sample_time_ns > after_ns}
    return set(names) <= seen


def bus_health(got):
    """The latest Health's "bus" stream."""
    return [s for m in got if type(m).__name__ == "Health" for s in m.streams if s.stream == "bus"][-1]


def running(studio):
    """The hub, its messages and the nodes; fails at once when the hub never published."""
    if not studio[3]:
        pytest.fail("the hub never published its nodes' samples (the first test says why)")
    return studio[:3]


def test_the_hub_publishes_the_nodes_samples_received_on_vcan0(studio):
    hub, messages, nodes, started = studio
    assert messages.until(batches_of, START_S, hub), \
        f"no ImuBatch with {sorted(NAMES.values())} from the hub on vcan0 (hub ended: {hub.poll()}, " \
        f"nodes ended: {nodes.poll()})"
    started.append(True)
    got = [s for m in messages.got if type(m).__name__ == "ImuBatch" for s in m.samples]
    assert all(abs(s.qw - 1.0) < 1e-3 and abs(s.az - 9.81) < 0.01 for s in got), "samples not the nodes' (still) ones"


def test_garbage_frames_are_counted_by_reason_not_fatal(studio):
    hub, messages, _ = running(studio)
    messages.until(lambda got: any(type(m).__name__ == "Health" for m in got), 5.0, hub)
    before = bus_health(messages.got).malformed
    for command in GARBAGE:
        sh(*command)
    sent = time.time_ns()
    assert messages.until(lambda got: bus_health(got).malformed >= before + UNKNOWN_IDS + BAD_LENGTHS, 20.0, hub), \
        f"the hub's bus malformed count went {before} -> {bus_health(messages.got).malformed}"
    assert messages.until(lambda got: batches_of(got, after_ns=sent), 20.0, hub), "no batches after the garbage"


def test_the_interface_down_is_counted_and_the_hub_goes_on_when_it_is_up(studio):
    hub, messages, _ = running(studio)
    before = bus_health(messages.got).bus_errors
    sh("ip", "link", "set", "vcan0", "down")
    try:
        messages.until(lambda got: bus_health(got).bus_errors > before, 20.0, hub)
    finally:
        sh("ip", "link", "set", "vcan0", "up")
    assert bus_health(messages.got).bus_errors > before, "sends on the interface down were not counted"
    up = time.time_ns()
    assert messages.until(lambda got: batches_of(got, after_ns=up), 30.0, hub), "no batches once vcan0 was up again"


def test_the_hub_and_the_nodes_end_cleanly_with_the_counts_by_reason(studio):
    hub, _, nodes = running(studio)
    err, nodes_err = stop(hub), stop(nodes)
    assert nodes.returncode == 0 and "node 3 running at 30 Hz; node 7 running at 30 Hz" in nodes_err, nodes_err
    assert hub.returncode == 0 and "Traceback" not in err, err
    dropped = ast.literal_eval(re.search(r"dropped (\{.*?\})", err).group(1))
    assert dropped.get("unknown_id") == UNKNOWN_IDS and dropped.get("bad_length") == BAD_LENGTHS, err
    assert "vcan0" in err and "Network is down" in err, f"the interface down was not reported: {err}"


def test_a_missing_interface_is_an_error_naming_it():
    from mocap_edge.errors import EdgeError
    from mocap_edge.hub.can_bus import open_bus

    with pytest.raises(EdgeError, match="socketcan:vcan9.*No such device"):
        open_bus("socketcan:vcan9")
