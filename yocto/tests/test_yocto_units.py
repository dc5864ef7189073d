"""The edge boxes' systemd units (edge/systemd) as the image installs them: verified by systemd's
own checker in a root that holds what the image holds (conftest.image_root), and their ExecStart
lines parsed by the commands they run, with the example settings a box is given."""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest

from mocap_edge.__main__ import parse_arguments
from mocap_edge.hub import bus_budget
from mocap_edge.hub.config import HubConfig

import layer_parse
from install_tree import edge_dist

SYSTEMD = layer_parse.REPO / "edge" / "systemd"
EXAMPLES = SYSTEMD / "examples"
DATA = "/data/mocap/"  # a box's settings; the examples stand in for them
UNITS = ["mocap-camera@0.service", "mocap-imu-hub.service", "mocap-clock-sync.service", "ptp4l@eth0.service"]
pytestmark = pytest.mark.skipif(not shutil.which("systemd-analyze"), reason="systemd-analyze missing: make setup")


def settings(unit: str) -> dict[str, list[str]]:
    """Key -> values of a unit file (a key may repeat)."""
    out: dict[str, list[str]] = {}
    for line in (SYSTEMD / unit).read_text().splitlines():
        if "=" in line and not line.startswith(("#", "[")):
            key, value = line.split("=", 1)
            out.setdefault(key.strip(), []).append(value.strip())
    return out


def environment(unit: str, instance: str) -> dict[str, str]:
    """Environment= then EnvironmentFile= (the example file standing for /data/mocap's)."""
    env = dict(e.split("=", 1) for v in settings(unit).get("Environment", []) for e in shlex.split(v))
    for path in settings(unit).get("EnvironmentFile", []):
        example = EXAMPLES / path.lstrip("-").replace("%i", instance).removeprefix(DATA)
        if example.exists():
            env.update(line.split("=", 1) for line in example.read_text().splitlines()
                       if "=" in line and not line.startswith("#"))
    return env


def exec_start(unit: str, instance: str = "0") -> list[str]:
    """ExecStart's words as systemd makes them: %i the instance, ${VAR} one word, $VAR split."""
    (line,) = settings(unit)["ExecStart"]
    env = environment(unit, instance)
    words = []
    for word in line.replace("%i", instance).split():
        if m := re.fullmatch(r"\$\{(\w+)\}", word):
            words.append(env.get(m[1], ""))
        elif m := re.fullmatch(r"\$(\w+)", word):
            words += env.get(m[1], "").split()
        else:
            words.append(word)
    return words


def test_the_box_units_run_the_edges_command_with_arguments_it_accepts():
    assert 'mocap-edge = "mocap_edge.__main__:main"' in edge_dist.pyproject([], [])  # the wheel's command
    for unit in ("mocap-camera@.service", "mocap-imu-hub.service"):
        argv = exec_start(unit)
        assert argv[0] == "/usr/bin/mocap-edge", unit
        parse_arguments(argv[1:])
    hub = exec_start("mocap-imu-hub.service")
    assert HubConfig.load(EXAMPLES / Path(hub[hub.index("--config") + 1]).name).names


def test_a_setting_the_box_would_refuse_is_refused():
    argv = exec_start("mocap-camera@.service")
    argv[argv.index("--trigger") + 1] = "/dev/gpiochip0"  # no line
    with pytest.raises(SystemExit):
        parse_arguments(argv[1:])


def test_the_can_bus_comes_up_at_the_hubs_bit_rate():
    network = (SYSTEMD / "80-mocap-can0.network").read_text()
    assert re.search(r"^BitRate=(\d+)$", network, re.M)[1] == str(bus_budget.BITRATE)


def verify(root: Path, *units: str) -> subprocess.CompletedProcess:
    return subprocess.run(["systemd-analyze", "verify", f"--root={root}", "--man=no", *units],
                          capture_output=True, text=True, timeout=120)


def test_systemd_verifies_the_units_in_the_image_root(image_root):
    if not (image_root / "usr/lib/systemd/system/ptp4l@.service").exists() or not shutil.which("ptp4l"):
        pytest.skip("linuxptp is not on this machine (make setup installs it)")
    result = verify(image_root, *UNITS)
    assert result.returncode == 0 and not result.stdout.strip() and not result.stderr.strip(), result.stderr


def test_a_unit_naming_a_missing_command_fails_verification(image_root, tmp_path):
    root = tmp_path / "root"
    shutil.copytree(image_root, root, symlinks=True)
    unit = root / "usr/lib/systemd/system/mocap-imu-hub.service"
    unit.write_text(unit.read_text().replace("/usr/bin/mocap-edge ", "/usr/bin/mocap-hub "))
    result = verify(root, "mocap-imu-hub.service")
    assert result.returncode != 0 and "/usr/bin/mocap-hub" in result.stderr
