"""The Python side of the wire formats' golden conformance vectors (tests/golden/)."""

import json
from pathlib import Path

import pytest
from google.protobuf import json_format

from mocap.net import wire

GOLDEN = Path(__file__).parent / "golden"
INDEX = json.loads((GOLDEN / "index.json").read_text())


@pytest.mark.parametrize("name", sorted(n for n, v in INDEX.items() if not v.get("rejected")))
def test_decodes_to_the_expected_message(name):
    entry = INDEX[name]
    data = (GOLDEN / f"{name}.bin").read_bytes()
    got = wire.decode([entry["type"].encode(), data])
    expected = json_format.Parse((GOLDEN / f"{name}.json").read_text(), wire.TYPES[entry["type"]]())
    # A relay keeps fields it does not know (they were appended last: same bytes).
    assert got.SerializeToString(deterministic=True) == data
    got.DiscardUnknownFields()
    assert got == expected


@pytest.mark.parametrize("name", sorted(n for n, v in INDEX.items() if v.get("rejected")))
def test_rejects_bad_bytes(name):
    with pytest.raises(wire.WireError) as e:
        wire.decode([INDEX[name]["type"].encode(), (GOLDEN / f"{name}.bin").read_bytes()])
    assert e.value.reason == "undecodable"


def test_wire_errors_name_the_reason():
    frame = wire.KeypointFrame(camera_id="cam0", detected=True)
    frame.persons.add(x=[1.0, float("nan")], y=[2.0, 3.0], confidence=[1.0, 1.0])
    cases = {
        "not_finite": [b"mocap.v1.KeypointFrame", frame.SerializeToString()],
        "wrong_version": [b"mocap.v2.KeypointFrame", b""],
        "unknown_type": [b"other.Thing", b""],
        "oversized": [b"mocap.v1.KeypointFrame", bytes(wire.MAX_PAYLOAD + 1)],
        "undecodable": [b"mocap.v1.KeypointFrame"],
        "invalid": wire.encode(wire.KeypointFrame(frame_index=3)),
    }
    for reason, frames in cases.items():
        with pytest.raises(wire.WireError) as e:
            wire.decode(frames)
        assert e.value.reason == reason, reason
    frame.persons[0].x[1] = 5.0
    assert wire.decode(wire.encode(frame)) == frame
