"""`mocap train-prior --bvh DIR --out FILE`: the PCA pose prior fitted to a folder of BVH clips."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from mocap import paths
from mocap.model import prior

log = logging.getLogger(__name__)


def register(sub: argparse._SubParsersAction) -> None:
    t = sub.add_parser("train-prior", help="fit the PCA pose prior to a folder of BVH clips")
    t.add_argument("--bvh", required=True, help="folder of BVH files (searched recursively)")
    t.add_argument("--out", required=True, help="prior JSON to write")
    t.add_argument("--split", default=str(paths.HOST_DATA / "motion_split.json"),
                   help="split file whose 'test' and 'validation' clips are left out (default: the shipped one)")
    t.add_argument("--include-test", action="store_true", help="train on the test and validation clips too")
    t.add_argument("--rate", type=float, default=60.0, help="resample clips to this rate, Hz (default 60)")
    t.add_argument("--clusters", type=int, default=500, help="k-means clusters, 0 for none (default 500)")
    t.add_argument("--variance", type=float, default=0.95, help="fraction of variance kept (default 0.95)")
    t.add_argument("--seed", type=int, default=0, help="k-means seed (default 0)")
    t.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    exclude = set() if args.include_test else prior.held_out_clips(Path(args.split))
    result, info = prior.train(Path(args.bvh), rate=args.rate, exclude=exclude, variance=args.variance,
                               clusters=args.clusters or None, seed=args.seed)
    prior.save(result, Path(args.out), info)
    log.info("wrote %s: %d clips, %d frames, rank %d", args.out, len(info["clips"]), info["frames"], info["rank"])
    return 0
