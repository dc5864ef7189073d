"""`mocap demo`: the live system on the built-in default, a simulated studio — 8 cameras
at 60 fps and 13 IMUs at 100 Hz played in real time over ZeroMQ on loopback, the C++
host solving live — ending with the take as BVH, joint CSV and a report."""

from __future__ import annotations

import sys
from pathlib import Path

from mocap import _core, live
from mocap.export.bvh import write_bvh
from mocap.export.joints_csv import write_positions_csv
from mocap.export.vmc import VmcSender


def _progress(health) -> None:
    cams = [s for s in health.streams if s.stream.startswith("camera/")]
    active = sum(s.active for s in cams)
    pose = next((s for s in health.streams if s.stream == "pose"), None)
    line = (f"\rmocap demo: {health.frames_solved:6d} frames solved, {pose.rate_hz if pose else 0:5.1f} fps, "
            f"{active}/{len(cams)} cameras, latency p50 {health.latency_p50_ms:4.2f} ms p99 {health.latency_p99_ms:4.2f} ms")
    print(line, end="" if sys.stderr.isatty() else "\n", file=sys.stderr, flush=True)


def calibration_line(studio: live.Studio, result: dict) -> str:
    if studio.calibration == "oracle":
        return "Calibration: the oracle (the simulation's true skeleton and IMU mounting)."
    if studio.calibration == "live":
        when = result.get("calibrated_from_s")
        after = result.get("calibrated", {}).get("joint_centres_pos_cm")
        return ("Calibration: live — mocapd started from video alone with the default skeleton; the live calibrator "
                "(`mocap calibrate --follow`) published the subject's calibration as soon as the IMUs had moved "
                "enough, estimated from the live streams (details in `session/calibrated/calibration.json`): "
                + ("never, in this take." if when is None else
                   f"solved with the IMUs from {when:.1f} s of the take on"
                   + ("" if after is None else f", joint centres {after:.2f} cm from then") + ". Published: "
                   + ", ".join(f"{'quick' if c['quick'] else 'full'} at {c['take_s']:.1f} s"
                               for c in result.get("calibrations", [])) + "."))
    return ("Calibration: estimated by the host from the take's first 5 s with motion (skeleton, IMU mountings, "
            "headings and positions; `docs/calibration.md`, details in `session/calibration.json`): nothing of the "
            "truth.")


def _largest(corrections: dict) -> str:
    if not corrections:
        return "n/a"
    name = max(corrections, key=lambda k: abs(corrections[k]))
    return f"{corrections[name]:+.1f} deg ({name})"


def report(result: dict, seconds: float, studio: live.Studio) -> str:
    def fmt(v, unit=""):
        return "n/a" if v is None else f"{v:.2f}{unit}"
    dropped = ", ".join(f"{k} {v}" for k, v in result["host_dropped"].items()) or "none"
    return "\n".join([
        "# mocap demo report", "",
        f"Simulated studio: Pose2Sim's Balancing trial (PyPI pose2sim 0.4.15, BSD-3) fitted to the skeleton and "
        f"looped to {seconds:.0f} s; {len(studio.camera_ids)} cameras at 60 fps (simulated detector errors), "
        f"13 IMUs at {live.IMU_RATE:.0f} Hz (simulated sensor errors); played in real time by one "
        "camera box per camera (the real box on the simulated backend) and an IMU hub over ZeroMQ on loopback; "
        "solved live by mocapd.", "",
        calibration_line(studio, result), "",
        "| figure | value |", "|---|---|",
        f"| frames captured | {result['frames']} |",
        f"| frames solved and received | {result['solved']} |",
        f"| frames dropped | {result['dropped']} |",
        f"| joint centre position error (mean, 13 joints) | {fmt(result.get('joint_centres_pos_cm'), ' cm')} |",
        f"| joint centre velocity error (mean) | {fmt(result.get('joint_centres_vel_cms'), ' cm/s')} |",
        f"| bone origin position error (mean, 21 bones) | {fmt(result.get('pos_error_cm'), ' cm')} |",
        f"| bone orientation error (mean) | {fmt(result.get('ori_error_deg'), ' deg')} |",
        f"| host latency p50 / p99 / max | {fmt(result['latency_p50_ms'])} / {fmt(result['latency_p99_ms'])} / "
        f"{fmt(result['latency_max_ms'], ' ms')} |",
        f"| inputs dropped by the host | {dropped} |",
        f"| heading tracking: largest correction at the end | {_largest(result['heading_corrections_deg'])} |", "",
        "Host latency: from the arrival of a frame's last input to the publication of its pose.", ""])


def run(out: Path, seconds: float, vmc: str | None = None, seed: int = 0, record: str | None = None,
        calibration: str = "estimated", still_s: float = 0.0) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    print(f"mocap demo: simulating {seconds:.0f} s of the studio into {out / 'session'}", file=sys.stderr)
    studio = live.prepare(out / "session", seconds, seed=seed, calibration=calibration, still_s=still_s)
    sender = None
    if vmc:
        host, _, port = vmc.partition(":")
        sender = VmcSender(studio.session_skeleton, host=host or "127.0.0.1", port=int(port or 39539))
    print(f"mocap demo: starting mocapd and {len(studio.camera_ids)} camera boxes + an IMU hub", file=sys.stderr)
    run_ = live.play(studio, progress=_progress,
                     on_pose=(lambda p: sender.send(list(p.theta), p.capture_time_ns * 1e-9)) if sender else None,
                     record=Path(record) if record else None)
    print(file=sys.stderr)
    result = live.score(studio, run_)
    if (studio.calibrated / "skeleton.json").is_file():  # the live calibrator's latest
        studio.session_skeleton = _core.Skeleton.load(str(studio.calibrated / "skeleton.json"))
    if len(result["thetas"]):
        write_bvh(out / "demo.bvh", studio.session_skeleton, result["thetas"], 60.0)
        write_positions_csv(out / "demo_joints.csv", studio.session_skeleton.bone_names, result["positions"],
                            result["times"])
    (out / "report.md").write_text(report(result, seconds, studio))
    print((out / "report.md").read_text(), file=sys.stderr)
    return result
