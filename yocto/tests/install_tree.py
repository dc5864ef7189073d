"""Paths of an installed edge (the tests' image root, conftest.image_root) and the edge's
distribution script, for the layer's tests."""

from __future__ import annotations

import sys
import sysconfig
from pathlib import Path

import layer_parse

sys.path.insert(0, str(layer_parse.REPO / "scripts"))

import edge_dist  # noqa: E402, F401  (scripts/edge_dist.py)


def site_packages(root: Path) -> Path:
    """Where pip puts the edge's packages under root (this interpreter's layout, prefix /usr)."""
    rel = Path(sysconfig.get_path("purelib", vars={"base": "/usr"})).relative_to("/")
    return root / rel
