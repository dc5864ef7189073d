"""`mocap solve`: a recording solved offline through the host's pipeline, or a take folder."""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

from mocap.errors import InputError
from mocap.io.session import Session
from mocap.recording import offline, published, reader
from mocap.takes import solve as take_solve


def register(sub: argparse._SubParsersAction) -> None:
    so = sub.add_parser("solve", help="solve a recording offline through the host's pipeline (--out a BVH), or a take "
                        "folder (--out a folder: joints.csv, take.bvh, calibration report)")
    so.add_argument("--recording", default=None, help="MCAP file of `mocap record` / `mocap demo --record`")
    so.add_argument("--take", default=None, help="take folder (docs/take_format.md)")
    so.add_argument("--session", default=None, help="session file (default: the one attached to the recording)")
    so.add_argument("--out", required=True, help="BVH to write (--recording; of several people, one per person: "
                    "_subjectID before the suffix, as --csv's) or output folder (--take)")
    so.add_argument("--csv", default=None, help="also write joint positions as CSV")
    so.add_argument("--set", action="append", default=[], metavar="OPTION=VALUE",
                    help="--take: a solver option of the solve after the calibration, e.g. motion.enabled=false "
                    "(repeatable)")
    so.set_defaults(func=run)


def _take(args: argparse.Namespace) -> int:
    report = take_solve.solve_take(Path(args.take), Path(args.out), args.set)
    print(json.dumps({"frames": report["frames"], "out": args.out, "skeleton_scales": report["skeleton"]["scales"]}),
          flush=True)
    return 0


def run(args: argparse.Namespace) -> int:
    if bool(args.recording) == bool(args.take):
        raise InputError("give exactly one of --recording FILE and --take DIR")
    if args.take:
        return _take(args)
    if args.set:
        raise InputError("--set is for --take (a recording is solved with its session's options)")
    with tempfile.TemporaryDirectory() as folder, reader.Recording(args.recording) as recording:
        session = Path(args.session) if args.session else recording.session(folder)
        if session is None:
            raise InputError(f"{args.recording}: no session is attached to this recording; give --session")
        poses, dropped, skeleton = offline.solve_recording(recording, session)
        suits = published.suit_skeletons(Session.load(session), skeleton)
    integrity = recording.integrity
    clock = (f"; {dropped['clock_offset']} inputs' times are not on their arrival's clock (recorded from a replay "
             "without --restamp?)") if dropped.get("clock_offset") else ""
    if not poses:
        raise InputError(f"{args.recording}: no frame could be solved (dropped inputs: {dropped}; the recording: "
                         f"{integrity.describe()}){clock}")
    if clock:
        print(f"mocap solve: warning: {args.recording}{clock}", file=sys.stderr)
    written = offline.write_poses(poses, skeleton, Path(args.out), Path(args.csv) if args.csv else None, suits)
    print(json.dumps({"frames": len(poses), "out": args.out, "files": [str(f) for f in written], "dropped": dropped,
                      "integrity": integrity.as_dict()}), flush=True)
    return 0
