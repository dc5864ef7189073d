"""`mocap demo`: the live system on a simulated studio, with its progress on stderr."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mocap.demo import run as demo


def register(sub: argparse._SubParsersAction) -> None:
    d = sub.add_parser("demo", help="the live system on a simulated studio: 8 cameras + 13 IMUs over loopback, "
                       "mocapd solving in real time; writes OUT/demo.bvh, demo_joints.csv, report.md")
    d.add_argument("--out", default="out", help="output folder (default out)")
    d.add_argument("--seconds", type=float, default=20.0, help="length of the take (default 20)")
    d.add_argument("--vmc", default=None, metavar="HOST:PORT", help="also stream the poses as VMC (OSC/UDP)")
    d.add_argument("--record", default=None, metavar="FILE", help="record every stream to this MCAP file")
    d.add_argument("--seed", type=int, default=0)
    d.add_argument("--calibration", default="estimated", choices=["estimated", "oracle", "live"],
                   help="estimated: calibrated from the streams' first 5 s with motion before the take (default); "
                        "live: mocapd starts from video alone and the live calibrator (mocap calibrate --follow) "
                        "calibrates, then refines, during the take; oracle: the truth")
    d.add_argument("--still-start", type=float, default=0.0, metavar="S",
                   help="the performer stands still for S seconds before moving")
    d.add_argument("--curve", action="store_true", help="every stream authenticated and encrypted with CURVE keys "
                   "(each device's key pair in OUT/session/keys; README, \"Securing the streams\"); off by default: "
                   "the simulated studio stays on loopback")
    d.add_argument("--monitor", default="127.0.0.1:8080", metavar="[HOST:]PORT",
                   help="serve the live view (`mocap monitor`) there during the take (default 127.0.0.1:8080: "
                        "open http://127.0.0.1:8080/); 'off': none")
    d.set_defaults(func=run)


def _progress(health) -> None:
    cams = [s for s in health.streams if s.stream.startswith("camera/")]
    active = sum(s.active for s in cams)
    pose = next((s for s in health.streams if s.stream == "pose"), None)
    line = (f"\rmocap demo: {health.frames_solved:6d} frames solved, {pose.rate_hz if pose else 0:5.1f} fps, "
            f"{active}/{len(cams)} cameras, latency p50 {health.latency_p50_ms:4.2f} ms p99 {health.latency_p99_ms:4.2f} ms")
    print(line, end="" if sys.stderr.isatty() else "\n", file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    result = demo.run(out, args.seconds, vmc=args.vmc, seed=args.seed, record=args.record,
                      calibration=args.calibration, still_s=args.still_start, progress=_progress,
                      curve=args.curve, monitor=None if args.monitor == "off" else args.monitor)
    print(file=sys.stderr)
    print((out / "report.md").read_text(), file=sys.stderr)
    return 0 if result["solved"] else 1
