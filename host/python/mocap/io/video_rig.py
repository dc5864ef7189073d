"""A trial's calibration file (a Calib*.toml of Pose2Sim / anipose, or a Qualisys .qca.txt)
read as the rig of its videos: the calibration's cameras in the order of the videos, matched
by name ("cam01" = "cam_01")."""

from __future__ import annotations

from pathlib import Path

from mocap import _core
from mocap.errors import InputError
from mocap.io import calib_qca, calib_toml


def _key(name: str) -> str:
    return "".join(ch for ch in name.lower() if ch.isalnum())


def rig_for(calib: Path, cameras: list[str]) -> _core.Rig:
    """The calibration's cameras in the order of the videos, matched by name ("cam01" = "cam_01")."""
    rig = calib_qca.load(calib) if calib.name.endswith(".qca.txt") else calib_toml.load(calib)
    by_key = {_key(c.name): c for c in rig.cameras}
    missing = [c for c in cameras if _key(c) not in by_key]
    if missing:
        raise InputError(f"{calib}: no camera for the video {missing[0]!r}; it has "
                         f"{', '.join(c.name for c in rig.cameras)}")
    chosen = []
    for name in cameras:
        cam = by_key[_key(name)]
        cam.name = name
        chosen.append(cam)
    return _core.Rig(chosen)
