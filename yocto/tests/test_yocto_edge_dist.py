"""The edge's distribution as the image gets it: the wheel python3-mocap-edge builds
(scripts/edge_dist.py, conftest.edge_wheel) installed under /usr of a root, the native parts
mocap-edge-libs builds (CMake, MOCAP_EDGE_BOX) installed beside it, and the result run by an
interpreter that sees nothing of this checkout."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

from install_tree import edge_dist, site_packages

REPO = edge_dist.REPO


def test_the_wheel_holds_the_edge_and_only_the_host_modules_it_imports(edge_wheel):
    names = zipfile.ZipFile(edge_wheel).namelist()
    modules = {n.removesuffix(".py").removesuffix("/__init__").replace("/", ".") for n in names if n.endswith(".py")}
    assert modules == set(edge_dist.closure()) | {f"mocap.v1.{p.stem}_pb2" for p in (REPO / "proto/mocap/v1").glob("*.proto")}
    assert {"mocap.net.wire", "mocap.net.transport", "mocap_edge.hub.can_db"} <= modules
    assert not modules & {"mocap.rotations", "mocap.net.vmc", "mocap.io", "mocap.model"}
    assert "mocap_edge/data/mocap_imu.dbc" in names and "mocap_edge/data/layouts/blazepose33.json" in names
    assert not [n for n in names if n.endswith(".so") or "/tests/" in n]


def run_installed(root: Path, code: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    """code run by this interpreter with only root's packages and the third-party ones (no site
    processing: the checkout's editable install is not seen)."""
    paths = [str(site_packages(root)), sysconfig.get_path("purelib"), sysconfig.get_path("platlib")]
    prelude = f"import sys; sys.path[:0] = {paths!r}\n"
    return subprocess.run([sys.executable, "-S", "-c", prelude + code], capture_output=True, text=True,
                          cwd=root, env={"PATH": os.environ["PATH"], **(env or {})}, timeout=120)


def test_the_installed_edge_finds_its_data_and_runs(image_root):
    code = """
from mocap_edge import resources
from mocap_edge.detect import layouts
from mocap_edge.hub.can_db import Database
import mocap.net.wire, mocap_edge.__main__
for p in (mocap_edge.__file__, mocap.net.wire.__file__, resources.layouts_dir(), resources.can_database()):
    assert str(p).startswith(sys.path[0]), p
assert len(layouts.load("blazepose33").names) == 33
assert {m.name for m in Database().db.messages} >= {"Sync", "Command"}
try:
    mocap_edge.__main__.main(["camera", "--help"])
except SystemExit as e:
    assert e.code == 0
print("ok")
"""
    result = run_installed(image_root, code)
    assert result.returncode == 0 and result.stdout.endswith("ok\n"), result.stderr


def test_the_models_are_found_where_the_models_recipe_puts_them(image_root):
    code = """
from mocap_edge.detect.blazepose import BlazePose
BlazePose()
print("ok")
"""
    assert run_installed(image_root, code).returncode != 0  # not in the wheel: the models recipe's
    models = REPO / "edge" / "models"
    result = run_installed(image_root, code, {"MOCAP_EDGE_MODELS": str(models)})
    assert result.returncode == 0, result.stderr


@pytest.fixture(scope="module")
def native_root(image_root, tmp_path_factory) -> Path:
    """The image root with mocap-edge-libs' CMake build installed into it."""
    if not shutil.which("cmake"):
        pytest.skip("cmake missing: make setup")
    build = tmp_path_factory.mktemp("edge-box-build")
    site = site_packages(image_root).relative_to(image_root / "usr")
    subprocess.run(["cmake", "-S", str(REPO), "-B", str(build), "-G", "Ninja", "-DMOCAP_EDGE_BOX=ON",
                    f"-DMOCAP_PYTHON_SITE={site}", "-DCMAKE_INSTALL_PREFIX=/usr", f"-DPython_EXECUTABLE={sys.executable}",
                    "-Wno-dev"], check=True, capture_output=True, timeout=300)
    subprocess.run(["cmake", "--build", str(build)], check=True, capture_output=True, timeout=900)
    subprocess.run(["cmake", "--install", str(build)], check=True, capture_output=True, timeout=120,
                   env={**os.environ, "DESTDIR": str(image_root)})
    return image_root


def test_the_hubs_filter_library_is_installed_beside_its_binding(native_root):
    code = """
from mocap_edge.hub.i2c import filter
assert str(filter.library_path()).startswith(sys.path[0]), filter.library_path()
filter.library()
print("ok")
"""
    result = run_installed(native_root, code)
    assert result.returncode == 0, result.stderr


def test_the_libcamera_capture_is_installed_beside_the_sources(native_root):
    if subprocess.run(["pkg-config", "--exists", "libcamera"]).returncode != 0:
        pytest.skip("libcamera-dev missing: make setup")
    code = """
import mocap_edge.sources._libcamera as lc
assert lc.__file__.startswith(sys.path[0]), lc.__file__
print("ok")
"""
    result = run_installed(native_root, code)
    assert result.returncode == 0, result.stderr
