"""`mocap eval-edge`: the edge detector and the video-only solve on the real Balancing trial."""

from __future__ import annotations

import argparse
import json

from mocap.eval import real_trial
from mocap.io.demo_data import fetch_trial


def register(sub: argparse._SubParsersAction) -> None:
    ee = sub.add_parser("eval-edge", help="the edge detector on the real Balancing trial (PCK against OpenPose, "
                        "speed) and the video-only solve of its keypoints against Pose2Sim's TRC")
    ee.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    print(json.dumps(real_trial.evaluate(fetch_trial()), indent=1), flush=True)
    return 0
