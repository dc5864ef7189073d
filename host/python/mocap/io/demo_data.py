"""Data from registry packages, cached under .cache/ by the setup step (needs nothing
built: `python -m mocap.io.demo_data`). The first two are Pose2Sim's "Balancing" demo trial
(PyPI, BSD-3-Clause, licence kept beside the files), the third its batch demo (`fetch_batch`), the
fourth its multi-person demo (`fetch_multiperson`):
- the demo's motion: its triangulated 3D keypoints (pose2sim 0.4.15), `fetch`;
- the real multi-camera trial for the edge detector's evaluation (`fetch_trial`): the four
  videos (pose2sim 0.10.49, Demo_SinglePerson: 100 frames at 60 fps, 1080 x 1920), and from
  0.4.15 the OpenPose BODY_25B detections of each camera, the Qualisys calibration and the
  triangulated TRC. Layout: videos/camNN.mp4, pose/camN_json/*.json, Calib_qualisys.toml,
  Balancing_for_IK.trc, LICENSE.
"""

from __future__ import annotations

import hashlib
import logging
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

from mocap import paths
from mocap.errors import DataMissingError

log = logging.getLogger(__name__)

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
    with _wheel(PACKAGE, dest / TRIAL) as z:
        dest.mkdir(parents=True, exist_ok=True)
        for member, (name, _) in MEMBERS.items():
            (dest / name).write_bytes(z.read(member))
    if not _complete(dest):
        raise DataMissingError(f"{PACKAGE}'s demo files in {dest} do not match their recorded SHA-256")
    return dest


TRIAL_CACHE = paths.REPO / ".cache" / "pose2sim-balancing"
VIDEOS = {  # pose2sim 0.10.49 member -> (cached name, SHA-256)
    f"Pose2Sim/Demo_SinglePerson/videos/cam0{c}.mp4": (f"videos/cam0{c}.mp4", sha) for c, sha in enumerate([
        "cf4f2816c86bea4bfbea255333d8626ff32a3ecabdab8b0fb147cea9167fde3a",
        "94ff87cf978b8406e8aa36ab3c5362e72848994e87652f0dc7a33c315e8e0442",
        "b8b329f832f178f27ecb78d024d5026b96c6adb36c387bfe2c0af85eab8a11ca",
        "b5c0e7863fd70d008e7178d3c556b045b0ea5f78fcd61ca548a0b2e807e641f7"], start=1)}
TRIAL_FILES = {  # pose2sim 0.4.15 member (or folder, ending in /) -> cached name
    "Pose2Sim/Demo/pose/": "pose/",
    "Pose2Sim/Demo/calibration/Calib_qualisys.toml": "Calib_qualisys.toml",
    "Pose2Sim/Demo/opensim/Balancing_for_IK.trc": TRIAL,
    "pose2sim-0.4.15.dist-info/LICENSE": "LICENSE",
}
TRIAL_DONE = ".complete"  # written last: the extraction finished


def fetch_trial(dest: Path = TRIAL_CACHE) -> Path:
    """The real Balancing trial (see the module docstring); downloads both wheels (~67 MB)
    only when the folder is incomplete or a video was altered."""
    if (dest / TRIAL_DONE).is_file() and _videos_intact(dest):
        return dest
    with _wheel("pose2sim==0.10.49", dest / "videos") as z:
        (dest / "videos").mkdir(parents=True, exist_ok=True)
        for member, (name, _) in VIDEOS.items():
            (dest / name).write_bytes(z.read(member))
    with _wheel(PACKAGE, dest / "pose") as z:
        for member, name in TRIAL_FILES.items():
            for m in [n for n in z.namelist() if n.startswith(member)] if member.endswith("/") else [member]:
                target = dest / name / m[len(member):] if member.endswith("/") else dest / name
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(z.read(m))
    (dest / TRIAL_DONE).write_text("pose2sim 0.10.49 videos + 0.4.15 detections, calibration, TRC\n")
    return dest


BATCH_CACHE = paths.REPO / ".cache" / "pose2sim-batch"
BATCH_MEMBERS = {"Pose2Sim/Demo_Batch/": "", "pose2sim-0.10.49.dist-info/licenses/LICENSE": "LICENSE"}
BATCH_TRIALS = ("Trial_1", "Trial_2")


def fetch_batch(dest: Path = BATCH_CACHE) -> Path:
    """Pose2Sim's batch demo (pose2sim 0.10.49, Demo_Batch): Trial_1/ and Trial_2/, four videos
    each (videos/camNN.mp4, 100 frames at 60 fps, 1080 x 1920), beside calibration/Calib.qca.txt
    (Qualisys), as Pose2Sim lays out a batch; downloaded (~40 MB) only when incomplete."""
    return _fetch_folder(dest, BATCH_MEMBERS, "pose2sim 0.10.49 Demo_Batch")


MULTI_CACHE = paths.REPO / ".cache" / "pose2sim-multiperson"
MULTI_MEMBERS = {"Pose2Sim/Demo_MultiPerson/": "", "pose2sim-0.10.49.dist-info/licenses/LICENSE": "LICENSE"}


def fetch_multiperson(dest: Path = MULTI_CACHE) -> Path:
    """Pose2Sim's multi-person demo (pose2sim 0.10.49, Demo_MultiPerson): videos/camNN.mp4 (four
    cameras, 100 frames at 60 fps, 1088 x 1920, two people) and calibration/Calib.qca.txt
    (Qualisys); downloaded (~40 MB wheel) only when incomplete."""
    return _fetch_folder(dest, MULTI_MEMBERS, "pose2sim 0.10.49 Demo_MultiPerson")


def _fetch_folder(dest: Path, members: dict[str, str], done: str) -> Path:
    """The pose2sim 0.10.49 wheel's members (a folder, ending "/", or a file) copied under dest
    by their names, once: `done` is written into its completion mark."""
    if (dest / TRIAL_DONE).is_file():
        return dest
    with _wheel("pose2sim==0.10.49", dest) as z:
        for member, name in members.items():
            for m in [n for n in z.namelist() if n.startswith(member) and not n.endswith("/")]:
                target = dest / name / m[len(member):] if member.endswith("/") else dest / name
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(z.read(m))
    (dest / TRIAL_DONE).write_text(done + "\n")
    return dest


def _videos_intact(dest: Path) -> bool:
    return all((dest / name).is_file() and hashlib.sha256((dest / name).read_bytes()).hexdigest() == sha
               for name, sha in VIDEOS.values())


class _wheel:
    """The wheel of `package` downloaded by pip into a temporary folder, opened as a zip."""

    def __init__(self, package: str, wanted: Path):
        self.package, self.wanted = package, wanted

    def __enter__(self) -> zipfile.ZipFile:
        self._tmp = tempfile.TemporaryDirectory()
        cmd = [sys.executable, "-m", "pip", "download", "-q", "--disable-pip-version-check", "--no-deps",
               self.package, "-d", self._tmp.name]
        try:
            subprocess.run(cmd, check=True, capture_output=True, text=True, timeout=900)
            self._zip = zipfile.ZipFile(next(Path(self._tmp.name).glob("*.whl")))
        except (OSError, subprocess.SubprocessError, StopIteration) as e:
            self._tmp.cleanup()
            detail = getattr(e, "stderr", None) or str(e)
            raise DataMissingError(f"{self.wanted} is absent and {self.package} could not be downloaded "
                                   f"(run `python -m mocap.io.demo_data` online): {detail.strip()}") from e
        return self._zip

    def __exit__(self, *exc) -> None:
        self._zip.close()
        self._tmp.cleanup()


def main() -> int:
    """Downloads both into .cache/ (scripts/setup.sh runs it); logs where they are."""
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    try:
        log.info("demo motion files in %s", fetch())
        log.info("real trial files in %s", fetch_trial())
        log.info("batch demo trials in %s", fetch_batch())
        log.info("multi-person demo in %s", fetch_multiperson())
    except DataMissingError as e:
        log.error("error: %s", e)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
