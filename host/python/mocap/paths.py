"""Where the project's files are. ../shared is optional (development and CI only)."""

from __future__ import annotations

import os
from pathlib import Path

from mocap.errors import DataMissingError

REPO = Path(__file__).resolve().parents[3]
HOST_DATA = REPO / "host" / "data"
DEFAULT_SKELETON = HOST_DATA / "skeleton_default.json"
LAYOUTS = HOST_DATA / "layouts"
IMU_SETS = {"13": HOST_DATA / "imus13.json", "6": HOST_DATA / "imus6.json"}


def shared_dir() -> Path:
    """The shared data folder: $MOCAP_SHARED, else ../shared beside the repository."""
    return Path(os.environ.get("MOCAP_SHARED", REPO.parent / "shared"))


def shared_file(relative: str) -> Path:
    path = shared_dir() / relative
    if not path.exists():
        raise DataMissingError(f"{path} is absent: ../shared (development data) is not here")
    return path
