"""atheris target: the IMU hub's configuration file hub.toml (mocap_edge.hub.config). Input: the
file's bytes. Allowed failure: EdgeError; a configuration read is written back and read again
to the same."""

import atheris

with atheris.instrument_imports(include=["mocap_edge.hub"]):
    from mocap_edge.errors import EdgeError
    from mocap_edge.hub.config import HubConfig

import _harness  # noqa: E402

PATH = _harness.scratch("mocap_fuzz_hub_") / "hub.toml"


def check(data: bytes) -> None:
    PATH.write_bytes(data)
    config = HubConfig.load(PATH)
    PATH.write_text(config.to_toml())
    assert HubConfig.load(PATH) == config


if __name__ == "__main__":
    _harness.main(check, (EdgeError,))
