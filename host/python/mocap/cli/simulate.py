"""`mocap simulate --take-out DIR`: a simulated take of the demo motion, or of a BVH clip, written as
a take folder."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mocap import paths
from mocap.sim import take_out

LAYOUTS = sorted(p.stem for p in paths.LAYOUTS.glob("*.json"))


def register(sub: argparse._SubParsersAction) -> None:
    sm = sub.add_parser("simulate", help="simulate a take of the demo motion (cameras + IMUs) and write it as a "
                        "take folder (docs/take_format.md), with its truth (truth.json) beside it")
    sm.add_argument("--take-out", required=True, metavar="DIR", help="take folder to write")
    sm.add_argument("--seconds", type=float, default=10.0,
                    help="length of the take (default 10; a clip may be shorter)")
    sm.add_argument("--motion", metavar="BVH", help="a BVH clip's motion instead of the demo's")
    sm.add_argument("--layout", default="blazepose33", choices=LAYOUTS,
                    help="the detector's keypoint layout (default blazepose33)")
    sm.add_argument("--preset", default="hq13", choices=["hq13", "hs13", "hq6", "hs6"],
                    help="cameras and IMU set, as `mocap eval` (default hq13)")
    sm.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    sm.add_argument("--calibration-pose", choices=["T", "N"],
                    help="start with 1 s of a T-pose (arms out) or N-pose (arms down) and a 0.5 s blend "
                         "into the motion: the calibration uses it (docs/calibration.md)")
    sm.add_argument("--still-start", type=float, default=0.0, metavar="S",
                    help="the performer stands still for S seconds first (a pose of the motion), then moves: "
                         "the calibration waits for motion (docs/calibration.md)")
    sm.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    print(json.dumps(take_out.run(Path(args.take_out), args.seconds, args.preset, args.seed,
                                  args.calibration_pose, args.still_start,
                                  Path(args.motion) if args.motion else None, args.layout)), flush=True)
    return 0
