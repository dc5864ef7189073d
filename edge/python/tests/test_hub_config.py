"""The IMU hub's configuration file (mocap_edge.hub.config): hub.toml checked, refused with
EdgeError whatever its bytes, and written back so that it reads the same."""

import pytest

from mocap_edge.errors import EdgeError
from mocap_edge.hub.config import HubConfig


def test_hub_toml_is_checked(tmp_path):
    path = tmp_path / "hub.toml"
    path.write_text('[hub]\nid = "hub1"\nrate_hz = 120\n\n[nodes]\n3 = "pelvis"\n7 = "forearm_l"\n')
    config = HubConfig.load(path)
    assert config.hub_id == "hub1" and config.rate_hz == 120 and config.names == {3: "pelvis", 7: "forearm_l"}
    for text, what in (('[hub]\nspeed = 3\n', "unknown key 'speed'"), ('[nodes]\n64 = "x"\n', "node ids"),
                       ('[nodes]\n1 = "a"\n2 = "a"\n', "each sensor name once"), ("[hub\n", "hub.toml"),
                       ('[hub]\nrate_hz = 500\n', "rate_hz 500"), ('[hub]\ngyro_range_dps = 300\n', "gyro_range_dps"),
                       ('[hub]\nrate_hz = 120\n[nodes]\n' + "".join(f'{i} = "s{i}"\n' for i in range(1, 18)),
                        "17 nodes at 120 Hz with 100 Syncs/s load the CAN bus 74% .*at most 13 nodes")):
        path.write_text(text)
        with pytest.raises(EdgeError, match=what):
            HubConfig.load(path)


def test_hub_toml_of_any_bytes_is_read_or_refused_with_edge_error(tmp_path):
    """Inputs the fuzzer found (tests/fuzz/fuzz_hub_config.py): bytes that are not UTF-8, values
    of the wrong type and tables that are not tables are refused with EdgeError; a name with
    quotes, backslashes or control characters is written back so that it reads the same."""
    path = tmp_path / "hub.toml"
    for data, what in ((b'[nodes]\n1\x15\x00\x00\x00p\xddlvis"\n', "codec"),
                       (b'[hub]\nrate_hz = "60"\n', "rate_hz '60' is not an integer"),
                       (b"[hub]\nmode = true\n", "mode True is not a string"),
                       (b"[hub]\nrate_hz = 60.5\n", "rate_hz 60.5 is not an integer"),
                       (b"hub = 3\n", r"\[hub\] is not a table"), (b"[nodes]\n1 = 2\n", "sensor names")):
        path.write_bytes(data)
        with pytest.raises(EdgeError, match=what):
            HubConfig.load(path)
    config = HubConfig({1: 'a"b\\c\x7f', 2: "d'e"}, hub_id="x\ny")
    path.write_text(config.to_toml())
    assert HubConfig.load(path) == config
