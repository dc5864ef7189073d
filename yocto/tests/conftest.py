"""What several of the layer's tests share: the edge's distribution built into a wheel the way
the python3-mocap-edge recipe builds it (scripts/edge_dist.py, then a PEP 517 build with the
project's backend), and a root file system holding what the image holds for the edge boxes'
services (this machine's systemd units, the installed wheel, the services recipe's files)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import layer_parse
from install_tree import edge_dist

HOST_UNITS = Path("/lib/systemd/system")


@pytest.fixture(scope="session")
def edge_wheel(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("edge-dist")
    edge_dist.assemble(tmp / "dist")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-build-isolation",
                    "--wheel-dir", str(tmp / "wheel"), str(tmp / "dist")], check=True, timeout=300)
    (wheel,) = (tmp / "wheel").glob("mocap_edge-*.whl")
    return wheel


@pytest.fixture(scope="session")
def image_root(tmp_path_factory, edge_wheel) -> Path:
    """A root with /usr/lib/systemd/system (this machine's units, as systemd-analyze needs its
    targets), the edge wheel installed under /usr, and the services recipe's do_install."""
    root = tmp_path_factory.mktemp("image-root")
    shutil.copytree(HOST_UNITS, root / "usr" / "lib" / "systemd" / "system", symlinks=True)
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-compile",
                    "--root", str(root), "--prefix", "/usr", str(edge_wheel)], check=True, timeout=300)
    d = layer_parse.bb.data.createCopy(layer_parse.parsed_layer(tmp_path_factory.mktemp("oe"))["mocap-box-services"])
    d.setVar("D", str(root))
    d.setVar("WORKDIR", str(tmp_path_factory.mktemp("services")))
    result = layer_parse.run_task(d, "do_install", {"PATH": os.environ["PATH"]})
    assert result.returncode == 0, result.stderr
    if shutil.which("ptp4l"):  # this machine's linuxptp stands in for the image's
        (root / "usr" / "sbin").mkdir(parents=True, exist_ok=True)
        shutil.copy2(shutil.which("ptp4l"), root / "usr" / "sbin" / "ptp4l")
    return root

