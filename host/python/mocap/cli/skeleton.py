"""`mocap skeleton --from-bvh FILE --out FILE`: a solver skeleton file from a BVH hierarchy."""

from __future__ import annotations

import argparse
import logging

from mocap import _core
from mocap.io import bvh, retarget

log = logging.getLogger(__name__)


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("skeleton", help="write a solver skeleton file from a BVH hierarchy")
    s.add_argument("--from-bvh", required=True, help="BVH file whose hierarchy gives the bone offsets")
    s.add_argument("--scale", default="auto", help="file units to metres, or 'auto' (default)")
    s.add_argument("--out", required=True, help="skeleton JSON to write")
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    motion = bvh.load(args.from_bvh)
    mapping = retarget.map_joints(motion, "auto" if args.scale == "auto" else float(args.scale))
    skeleton = _core.Skeleton.from_bones(retarget.BONES, mapping.parents, mapping.offsets)
    with open(args.out, "w") as f:
        f.write(skeleton.to_json() + "\n")
    log.info("wrote %s (units scale %.6g, rest height %.3f m)", args.out, mapping.scale, skeleton.rest_height())
    return 0
