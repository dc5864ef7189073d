"""`mocap batch TAKE... --out DIR`: many takes solved as tasks on Dask distributed (mocap.batch)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from mocap.batch import inputs, runner, summary
from mocap.batch.task import Options
from mocap.takes.export import FORMATS


def register(sub: argparse._SubParsersAction) -> None:
    ba = sub.add_parser("batch", help="solve many takes (take folders, recordings) as tasks on Dask: this machine's "
                        "cores, or a cluster; each calibrated, solved, exported and reported into OUT/<take>/")
    ba.add_argument("takes", nargs="+", metavar="TAKE", help="take folders (docs/take_format.md) and MCAP "
                    "recordings of live takes (calibrated from their own first seconds, as `mocap calibrate`)")
    ba.add_argument("--out", required=True, help="output folder: OUT/<take>/ as `mocap solve --take` writes it, "
                    "with batch.json (its result); OUT/summary.md and summary.json")
    ba.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler (tcp://host:8786): its "
                    "workers solve the takes, reading them and writing OUT at the same paths (a shared file system); "
                    "default: a LocalCluster of this machine")
    ba.add_argument("--workers", type=int, help="the LocalCluster's worker processes (default: one per core)")
    ba.add_argument("--export", action="append", default=[], choices=sorted(FORMATS), metavar="FORMAT",
                    help="also write OUT/<take>/take.<ext> in this format (repeatable): " + ", ".join(sorted(FORMATS)))
    ba.add_argument("--set", action="append", default=[], metavar="OPTION=VALUE",
                    help="take folders: a solver option of the solve after the calibration (repeatable)")
    ba.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    takes = inputs.inputs(args.takes)
    if args.scheduler and args.workers is not None:
        print("mocap batch: --workers is for the LocalCluster; the cluster at --scheduler has its own",
              file=sys.stderr)
    started = time.monotonic()
    options = Options(exports=tuple(dict.fromkeys(args.export)), settings=tuple(args.set))
    results = runner.run(takes, Path(args.out), options, args.scheduler, args.workers)
    totals = summary.write(Path(args.out).resolve(), results, time.monotonic() - started)
    print(summary.table(results), end="", flush=True)
    print(f"mocap batch: {totals['ok']} of {totals['takes']} takes solved ({totals['skipped']} solved before), "
          f"{totals['failed']} failed, {totals['wall_s']:.1f} s; {Path(args.out) / 'summary.json'}", file=sys.stderr)
    return 1 if totals["failed"] else 0
