"""The `mocap` command: one entry point for every part of the system, one module per
subcommand (each `register`s its parser and `run`s it)."""

from __future__ import annotations

import argparse
import errno
import logging
import sys

from mocap.cli import (batch, bench, calibrate, calibrate_rig, demo, detect, eval_edge, eval_imu_filter, export,
                       imu_filter, imu_stats, keys, monitor, record, recover, replay, rig, simulate, skeleton, solve,
                       train_prior)
from mocap.cli import eval as evaluate
from mocap.errors import MocapError
from mocap_edge.errors import EdgeError

# In the order `mocap --help` lists them.
COMMANDS = (bench, skeleton, train_prior, evaluate, imu_stats, demo, calibrate, calibrate_rig, simulate, detect, eval_edge,
            solve, batch, export, record, replay, monitor, recover, keys, imu_filter, eval_imu_filter, rig)


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
    except OSError as e:  # a file or a device: a message naming it, no traceback
        print(f"mocap {args.command}: {describe_os_error(e, getattr(args, 'out', None))}", file=sys.stderr)
        return 2
    except (MocapError, EdgeError, ValueError) as e:  # bad input, named by the raiser
        print(f"mocap {args.command}: {e}", file=sys.stderr)
        return 2


def describe_os_error(e: OSError, out: str | None) -> str:
    """The file and the problem: an error of writing names no file (a full disk is found at a
    write or a close), so it is said to be about the command's output, `out`, when it has one."""
    if e.filename is not None:
        return f"{e.filename}: {e.strerror or e}"
    if out is not None and e.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO):
        return f"{out}: writing the output failed ({e.strerror}); what was written is incomplete"
    return str(e)


if __name__ == "__main__":
    sys.exit(main())
