"""`mocap demo`: the live system on the built-in default, a simulated studio — 8 cameras
at 60 fps and 13 IMUs at 100 Hz played in real time over ZeroMQ on loopback, the C++
host solving live — ending with the take as BVH, joint CSV and a report."""

from __future__ import annotations

import logging
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from mocap import _core, processes
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


def start_monitor(prepared: studio.Studio, http: str) -> tuple[subprocess.Popen, str] | None:
    """`mocap monitor` on mocapd's output, serving its page at `http` ([HOST:]PORT), ending with
    this process, and its page's URL; None (and a warning) when it cannot serve there: the demo
    goes on without it."""
    monitor = subprocess.Popen([sys.executable, "-m", "mocap.cli", "monitor", "--session", str(prepared.session),
                                "--http", http], stdout=subprocess.PIPE, text=True,
                               preexec_fn=processes.die_with_parent())
    ready = monitor.stdout.readline().split()  # "mocap monitor: URL", or nothing when it failed
    if len(ready) != 3:
        log.warning("mocap demo: no live view (mocap monitor stopped with status %s; its error is above)",
                    monitor.wait())
        return None
    log.info("mocap demo: the live view is at %s (open it in a browser)", ready[2])
    return monitor, ready[2]


def run(out: Path, seconds: float, vmc: str | None = None, seed: int = 0, record: str | None = None,
        calibration: str = "estimated", still_s: float = 0.0, progress: Callable | None = None,
        curve: bool = False, monitor: str | None = None) -> dict:
    """Prepares and plays the studio into `out` (session/, demo.bvh, demo_joints.csv,
    report.md); progress(health) once a second; curve: every stream with CURVE keys; monitor:
    [HOST:]PORT where the live view is served during the take. The result of mocap.demo.score."""
    out.mkdir(parents=True, exist_ok=True)
    log.info("mocap demo: simulating %.0f s of the studio into %s", seconds, out / "session")
    prepared = studio.prepare(out / "session", seconds, seed=seed, calibration=calibration, still_s=still_s,
                            curve=curve)
    sender = _vmc_sender(vmc, prepared.session_skeleton)
    page = start_monitor(prepared, monitor) if monitor else None  # (process, url)
    log.info("mocap demo: starting mocapd and %d camera boxes + an IMU hub", len(prepared.camera_ids))
    try:
        played = play.play(prepared, progress=progress,
                           on_pose=(lambda p: sender.send(list(p.theta), p.capture_time_ns * 1e-9)) if sender else None,
                           record=Path(record) if record else None)
    finally:
        if page is not None:
            page[0].terminate()
            page[0].wait(timeout=10)
    result = score.score(prepared, played)
    if (prepared.calibrated / "skeleton.json").is_file():  # the live calibrator's latest
        prepared.session_skeleton = _core.Skeleton.load(str(prepared.calibrated / "skeleton.json"))
    if len(result["thetas"]):
        write_bvh(out / "demo.bvh", prepared.session_skeleton, result["thetas"], 60.0)
        write_positions_csv(out / "demo_joints.csv", prepared.session_skeleton.bone_names, result["positions"],
                            result["times"])
    (out / "report.md").write_text(report(result, seconds, prepared))
    return result
