"""The hub's side of the CAN protocol's golden vectors (tests/golden/can_frames.txt):
cantools, reading proto/can/mocap_imu.dbc, decodes every frame to the listed values and
encodes the values back to the same bytes. The node's side: firmware/tests/test_can_golden.c."""

from pathlib import Path

import cantools
import pytest

ROOT = Path(__file__).resolve().parents[1]
DB = cantools.database.load_file(ROOT / "proto/can/mocap_imu.dbc")
NODE_ID_MASK = 0x3F  # a node's identifiers are the message's base + node id (1..63)


def _vectors():
    for number, line in enumerate((ROOT / "tests/golden/can_frames.txt").read_text().splitlines(), 1):
        if line and not line.startswith("#"):
            name, node_id, identifier, data, *fields = line.split()
            values = {k: float(v) for k, v in (f.split("=") for f in fields)}
            yield pytest.param(name, int(node_id), int(identifier, 16), bytes.fromhex(data), values,
                               id=f"{number}-{name}")


@pytest.mark.parametrize("name, node_id, identifier, data, values", _vectors())
def test_cantools_decodes_and_encodes_the_golden_frame(name, node_id, identifier, data, values):
    message = DB.get_message_by_frame_id(identifier & ~NODE_ID_MASK)
    assert message.name == name
    assert identifier == message.frame_id + (node_id if name != "Sync" else 0)
    assert len(data) == message.length
    assert message.decode(data, decode_choices=False) == values
    assert message.encode(values) == data


def test_every_message_of_the_database_has_a_vector():
    names = {p.values[0] for p in _vectors()}
    assert names == {m.name for m in DB.messages}


def test_node_ids_cannot_alias_another_message():
    # Every base leaves the low six bits free, so base + node id never reaches the next base.
    bases = sorted(m.frame_id for m in DB.messages)
    assert all(b & NODE_ID_MASK == 0 for b in bases)
    assert all(b2 - b1 > NODE_ID_MASK for b1, b2 in zip(bases, bases[1:]))
