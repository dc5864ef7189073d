"""`mocap eval-edge`: the edge detector and the video-only solve on the real Balancing trial,
or (--take-solve) the trial's OpenPose detections as a take folder solved by `mocap solve --take`."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mocap.eval import balancing_take, real_trial
from mocap.io.demo_data import fetch_trial


def register(sub: argparse._SubParsersAction) -> None:
    ee = sub.add_parser("eval-edge", help="the edge detector on the real Balancing trial (PCK against OpenPose, "
                        "speed) and the video-only solve of its keypoints against Pose2Sim's TRC")
    ee.add_argument("--take-solve", metavar="OUT", default=None,
                    help="instead: the trial's OpenPose BODY_25B detections written as a take folder (OUT/take), "
                    "solved by `mocap solve --take` (OUT/solved) and compared with Pose2Sim's TRC (distance of "
                    "the joint centres, jitter); no detector run")
    ee.add_argument("--self-calibrate", metavar="HEIGHT", type=float, default=None,
                    help="with --take-solve: the take's cameras calibrated from its own detections (`mocap "
                    "calibrate-rig`, the person HEIGHT metres tall) instead of the trial's board calibration; "
                    "the joints are compared in the board's world (the camera centres' similarity), and the rigs "
                    "too. Without --take-solve: the cameras also calibrated from the detector's keypoints, "
                    "compared with the board's")
    ee.add_argument("--set", action="append", default=[], metavar="OPTION=VALUE",
                    help="a solver option of the video-only solve (with --take-solve: of the solve after the "
                    "calibration), e.g. motion.enabled=false (repeatable)")
    ee.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if args.take_solve and args.self_calibrate is not None:
        result = balancing_take.evaluate_self_calibrated(fetch_trial(), Path(args.take_solve), args.self_calibrate,
                                                         args.set)
    elif args.take_solve:
        result = balancing_take.evaluate(fetch_trial(), Path(args.take_solve), args.set)
    else:
        result = real_trial.evaluate(fetch_trial(), args.set, args.self_calibrate)
    print(json.dumps(result, indent=1), flush=True)
    return 0
