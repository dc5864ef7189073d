"""The `mocap` command: one entry point for every part of the system, one module per
subcommand (each `register`s its parser and `run`s it)."""

from __future__ import annotations

import argparse
import logging
import sys

from mocap.cli import (bench, calibrate, demo, detect, eval_edge, eval_imu_filter, imu_filter, imu_stats, keys,
                       record, recover, replay, rig, simulate, skeleton, solve, train_prior)
from mocap.cli import eval as evaluate
from mocap.errors import MocapError
from mocap_edge.errors import EdgeError

# In the order `mocap --help` lists them.
COMMANDS = (bench, skeleton, train_prior, evaluate, imu_stats, demo, calibrate, simulate, detect, eval_edge, solve,
            record, replay, recover, keys, imu_filter, eval_imu_filter, rig)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="mocap", description="Real-time motion capture from video and IMUs.")
    p.add_argument("-v", "--verbose", action="store_true", help="log debug messages")
    sub = p.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.register(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.DEBUG if args.verbose else logging.INFO, format="%(levelname)s %(message)s")
    try:
        return args.func(args)
    except (MocapError, EdgeError, OSError, ValueError) as e:
        print(f"mocap {args.command}: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
