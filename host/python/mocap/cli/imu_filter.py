"""`mocap imu-filter --in IN.csv --out OUT.csv`: the IMU node's orientation filter on a recording."""

from __future__ import annotations

import argparse
import json

from mocap.imu_node import filter as node_filter


def register(sub: argparse._SubParsersAction) -> None:
    imf = sub.add_parser("imu-filter", help="run the IMU node's orientation filter (the firmware's C) on a recording: "
                         "IN.csv t,gx,gy,gz (rad/s),ax,ay,az (m/s^2),mx,my,mz (uT), sensor frame -> OUT.csv "
                         "t,qw,qx,qy,qz (sensor -> ENU)")
    imf.add_argument("--in", dest="input", required=True, metavar="IN.csv", help="recording, header row first; the "
                     "sample period is the median dt (each dt within 5 %% of it); a NaN value skips that vector")
    imf.add_argument("--out", required=True, metavar="OUT.csv", help="orientations to write, one row per input row")
    imf.add_argument("--no-mag", action="store_true", help="6D: ignore the magnetometer (heading from the gyroscope)")
    imf.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    print(json.dumps(node_filter.filter_csv(args.input, args.out, use_mag=not args.no_mag)), flush=True)
    return 0
