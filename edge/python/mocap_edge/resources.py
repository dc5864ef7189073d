"""Where the edge's data files are. In a checkout: the repository's own (host/data/layouts, shared
with the host solver; proto/can/mocap_imu.dbc, shared with the firmware; edge/models). In an
installed box (the edge distribution that scripts/edge_dist.py assembles and the Yocto layer
builds): the layouts and the CAN database as package data beside this module, the keypoint
models in <prefix>/share/mocap-edge/models. An environment variable overrides each:
MOCAP_CAN_DBC (the CAN database file), MOCAP_EDGE_MODELS (the folder holding the models' folders)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from mocap_edge.errors import EdgeError

REPO = Path(__file__).resolve().parents[3]
PACKAGE_DATA = Path(__file__).with_name("data")


def _first(what: str, candidates: list[Path]) -> Path:
    for path in candidates:
        if path.exists():
            return path
    raise EdgeError(f"{what} not found (looked at {', '.join(map(str, candidates))})")


def layouts_dir() -> Path:
    """The folder of the keypoint layout files (<name>.json)."""
    return _first("the keypoint layouts", [PACKAGE_DATA / "layouts", REPO / "host" / "data" / "layouts"])


def can_database() -> Path:
    """The sensor nodes' CAN database (mocap_imu.dbc)."""
    env = os.environ.get("MOCAP_CAN_DBC")
    candidates = [Path(env)] if env else [PACKAGE_DATA / "mocap_imu.dbc", REPO / "proto" / "can" / "mocap_imu.dbc"]
    return _first("the CAN database", candidates)


def models_dir(name: str) -> Path:
    """The folder of one keypoint model's files, e.g. models_dir("blazepose")."""
    env = os.environ.get("MOCAP_EDGE_MODELS")
    roots = [Path(env)] if env else [REPO / "edge" / "models", Path(sys.prefix) / "share" / "mocap-edge" / "models"]
    return _first(f"the {name} model", [root / name for root in roots])
