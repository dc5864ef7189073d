"""`mocap demo`: the live system on the built-in default, a simulated studio — 8 cameras
at 60 fps and 13 IMUs at 100 Hz played in real time over ZeroMQ on loopback, the C++
host solving live — ending with the take as BVH, joint CSV and a report."""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path

from mocap import _core
from mocap.demo import play, score, studio
from mocap.demo.report import report
from mocap.io.bvh_export import write_bvh
from mocap.io.joints_csv import write_positions_csv
from mocap.net.vmc import VmcSender

log = logging.getLogger(__name__)


def _vmc_sender(vmc: str | None, skeleton: _core.Skeleton) -> VmcSender | None:
    if not vmc:
        return None
    host, _, port = vmc.partition(":")
    return VmcSender(skeleton, host=host or "127.0.0.1", port=int(port or 39539))


def run(out: Path, seconds: float, vmc: str | None = None, seed: int = 0, record: str | None = None,
        calibration: str = "estimated", still_s: float = 0.0, progress: Callable | None = None,
        curve: bool = False) -> dict:
    """Prepares and plays the studio into `out` (session/, demo.bvh, demo_joints.csv,
    report.md); progress(health) once a second; curve: every stream with CURVE keys. The result of
    mocap.demo.score."""
    out.mkdir(parents=True, exist_ok=True)
    log.info("mocap demo: simulating %.0f s of the studio into %s", seconds, out / "session")
    prepared = studio.prepare(out / "session", seconds, seed=seed, calibration=calibration, still_s=still_s,
                            curve=curve)
    sender = _vmc_sender(vmc, prepared.session_skeleton)
    log.info("mocap demo: starting mocapd and %d camera boxes + an IMU hub", len(prepared.camera_ids))
    played = play.play(prepared, progress=progress,
                       on_pose=(lambda p: sender.send(list(p.theta), p.capture_time_ns * 1e-9)) if sender else None,
                       record=Path(record) if record else None)
    result = score.score(prepared, played)
    if (prepared.calibrated / "skeleton.json").is_file():  # the live calibrator's latest
        prepared.session_skeleton = _core.Skeleton.load(str(prepared.calibrated / "skeleton.json"))
    if len(result["thetas"]):
        write_bvh(out / "demo.bvh", prepared.session_skeleton, result["thetas"], 60.0)
        write_positions_csv(out / "demo_joints.csv", prepared.session_skeleton.bone_names, result["positions"],
                            result["times"])
    (out / "report.md").write_text(report(result, seconds, prepared))
    return result
