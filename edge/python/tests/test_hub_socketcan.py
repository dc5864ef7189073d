"""The hub's service on a real machine's CAN stack: what python-can hands it from SocketCAN."""

import can
import numpy as np
import pytest

from mocap_edge.hub.config import HubConfig
from mocap_edge.hub.hub import Hub
from mocap_edge.hub.service import HubService
from mocap_edge.hub.sim.bus import make_nodes

NAMES = {3: "pelvis"}


def test_frames_another_process_of_this_machine_sent_are_received():
    """python-can marks every frame sent from this machine as not received (SocketCAN's vcan, a
    can-utils tool on the hub's box): only the kinds the hub sends are taken as its echoes."""
    service = HubService(None, Hub(HubConfig(dict(NAMES))), lambda message: None)
    node = make_nodes([3], np.random.default_rng(0), origin_ns=0)[3]
    frame_id, data = node.heartbeat(1_000_000)
    service._receive(can.Message(arbitration_id=frame_id, data=data, is_extended_id=False, is_rx=False, timestamp=1.0))
    assert 3 in service.hub.nodes and service.hub.nodes[3].heartbeat
    for frame_id, data in (service.hub.db.sync(0), service.hub.db.command(3, "start")):
        service._receive(can.Message(arbitration_id=frame_id, data=data, is_extended_id=False, is_rx=False,
                                     timestamp=2.0))
    assert service.hub.frames == 1 and not service.hub.dropped  # the echoes were not fed as the nodes' frames


def test_the_simulated_nodes_command_names_what_it_cannot_open(capsys):
    from mocap_edge.hub.sim import runner

    assert runner.main(["--can", "socketcan:nosuchcan0", "--nodes", "3,7"]) == 1
    assert "--can socketcan:nosuchcan0" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        runner.main(["--can", "socketcan:vcan0", "--nodes", "3,64"])
    assert "node ids 1..63" in capsys.readouterr().err
