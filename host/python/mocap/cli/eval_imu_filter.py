"""`mocap eval-imu-filter`: the node's filter, VQF and Fusion on the BROAD benchmark."""

from __future__ import annotations

import argparse
import json

from mocap.imu_node import broad


def register(sub: argparse._SubParsersAction) -> None:
    eif = sub.add_parser("eval-imu-filter", help="the node's filter (9D, 6D), VQF and Fusion on the BROAD benchmark "
                         "(../shared/data/imu/broad): RMSE in degrees (docs/firmware.md)")
    eif.add_argument("--trials", nargs="+", default=None, metavar="NN",
                     help="trial numbers, e.g. 02 03 (default all 18; tuning: 01 04 06 08 10 24 26 28)")
    eif.add_argument("--methods", nargs="+", default=None, metavar="METHOD",
                     help="a subset of: 'ours 9D' 'ours 6D' 'VQF 9D' 'VQF 6D' 'Fusion 9D' (default all)")
    eif.add_argument("--markdown", action="store_true", help="print the tables (held-out, all, per trial) as Markdown")
    eif.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    rows = broad.evaluate(broad.load(args.trials), args.methods)
    if args.markdown:
        print(broad.markdown(rows), end="", flush=True)
        return 0
    sets = {"held-out": broad.HELD_OUT, "tuning": broad.TUNING, "all": tuple(rows)}
    print(json.dumps({"trials": rows, "summary": {name: broad.summarise(rows, numbers) for name, numbers in sets.items()}},
                     indent=1), flush=True)
    return 0
