"""`mocap recover IN.mcap OUT.mcap`: a recording cut short (its recorder killed, its disk
full) or damaged, written again as a whole indexed MCAP file."""

from __future__ import annotations

import argparse
import json

from mocap.recording import recover


def register(sub: argparse._SubParsersAction) -> None:
    rec = sub.add_parser("recover", help="write the intact messages and attachments of a recording cut short or "
                         "damaged as a whole, indexed MCAP file, and say what was lost")
    rec.add_argument("file", help="the MCAP file to recover (it is only read)")
    rec.add_argument("out", help="the MCAP file to write")
    rec.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    integrity = recover.recover(args.file, args.out)
    print(json.dumps({"file": args.file, "out": args.out, "integrity": integrity.as_dict()}), flush=True)
    return 0
