"""The package's rooms as installed: pyproject's `packages` names every subpackage (an
editable install and a wheel find only those), and each room says what it holds."""

import importlib
import tomllib

from mocap import paths


def _subpackages(root, prefix: str) -> set[str]:
    return {prefix + "." + ".".join(p.parent.relative_to(root).parts) if p.parent != root else prefix
            for p in root.rglob("__init__.py") if "__pycache__" not in p.parts}


def test_pyproject_lists_every_subpackage():
    config = tomllib.loads((paths.REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    found = set()
    for name, folder in config["package-dir"].items():
        found |= _subpackages(paths.REPO / folder, name)
    assert set(config["packages"]) == found


def test_every_room_has_a_docstring():
    for room in ("net", "io", "model", "recording", "calibration", "sim", "takes", "eval", "demo", "cli", "imu_node", "monitor"):
        assert (importlib.import_module(f"mocap.{room}").__doc__ or "").strip(), room
