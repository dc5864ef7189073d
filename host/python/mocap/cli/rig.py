"""`mocap rig --from-calib-toml FILE --out FILE`: a rig file from a Pose2Sim/anipose Calib.toml."""

from __future__ import annotations

import argparse
import logging

from mocap.io import calib_toml

log = logging.getLogger(__name__)


def register(sub: argparse._SubParsersAction) -> None:
    r = sub.add_parser("rig", help="write a rig file from a Pose2Sim/anipose Calib.toml")
    r.add_argument("--from-calib-toml", required=True, help="Calib.toml to read")
    r.add_argument("--out", required=True, help="rig JSON to write")
    r.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    rig = calib_toml.load(args.from_calib_toml)
    with open(args.out, "w") as f:
        f.write(rig.to_json() + "\n")
    log.info("wrote %s (%d cameras)", args.out, len(rig.cameras))
    return 0
