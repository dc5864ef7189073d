"""`mocap export SOLVED --format trc|c3d|gltf|bvh|csv --out FILE`: a solve as files other tools
open (mocap.takes.export)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mocap.takes.export import BVH_UNITS, FORMATS, export


def register(sub: argparse._SubParsersAction) -> None:
    ex = sub.add_parser("export", help="write a solve as TRC (OpenSim, Pose2Sim), C3D, CSV, binary glTF or BVH")
    ex.add_argument("solved", help="`mocap solve --take`'s output folder; its joint-position CSV (trc, c3d, csv) "
                    "or BVH (gltf, bvh); or a recording of a live take with mocapd's poses (.mcap: every format)")
    ex.add_argument("--format", required=True, choices=sorted(FORMATS),
                    help="; ".join(f"{k}: {v}" for k, v in FORMATS.items()))
    ex.add_argument("--out", required=True, help="the file to write (gltf: a .glb)")
    ex.add_argument("--subject", type=int, default=None, metavar="ID",
                    help="a recording of several people: only this person (mocapd's subject id), written to OUT; "
                    "default: every person, each to OUT's name with _subjectID before its suffix")
    ex.add_argument("--bvh-units", choices=sorted(BVH_UNITS), default="cm",
                    help="gltf from a BVH: its length unit (default cm, as `mocap solve` writes)")
    ex.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    summary = export(Path(args.solved), args.format, Path(args.out), args.bvh_units, args.subject)
    print(json.dumps({"out": args.out, "format": args.format, **summary}), flush=True)
    return 0
