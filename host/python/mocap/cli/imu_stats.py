"""`mocap imu-stats`: noise and bias figures of the real IMU recordings (for the simulator)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mocap import paths
from mocap.sim import imu_stats


def register(sub: argparse._SubParsersAction) -> None:
    i = sub.add_parser("imu-stats", help="noise and bias figures of the real IMU recordings (for the simulator)")
    i.add_argument("--imu", default=None, help="folder of the recordings (default ../shared/data/imu)")
    i.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    folder = Path(args.imu) if args.imu else paths.shared_file("data/imu")
    print(json.dumps(imu_stats.stats(folder), indent=1), flush=True)
    return 0
