"""`mocap calibrate`: a session calibrated from a recording or the live streams, or the live
calibrator beside mocapd (--follow)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mocap.calibration import from_recording, live
from mocap.errors import InputError


def register(sub: argparse._SubParsersAction) -> None:
    ca = sub.add_parser("calibrate", help="a live session whose skeleton and IMU mounting, heading and position are "
                        "estimated from the first seconds with motion of a recording or of the live streams "
                        "(docs/calibration.md)")
    ca.add_argument("--recording", help="MCAP file of `mocap record` / `mocap demo --record`")
    ca.add_argument("--connect", nargs="+", metavar="EP", help="instead: record live from these publishers (edge "
                    "boxes, IMU hubs; needs --session) until the IMUs moved enough, kept as OUT/calibration.mcap")
    ca.add_argument("--session", default=None, help="session giving rig, layout, IMU names and bones, endpoints "
                    "(default: the one attached to the recording)")
    ca.add_argument("--out", required=True, help="folder for the calibrated session (session.json and its files)")
    ca.add_argument("--seconds", type=float, default=5.0, help="length of the calibration window (default 5)")
    ca.add_argument("--span", nargs=2, type=int, metavar=("FIRST_NS", "LAST_NS"),
                    help="--recording: only the messages that arrived in this span (a live calibration's "
                         "span_ns, from calibration.json, repeats it)")
    ca.add_argument("--max-seconds", type=float, default=30.0,
                    help="--connect: stop recording after this long even if the IMUs barely moved (default 30); "
                         "--follow: calibrate after this long from seconds that move less")
    ca.add_argument("--follow", action="store_true",
                    help="with --connect: keep running beside mocapd, publish a Calibration on --publish as soon as "
                         "the IMUs moved enough and a refined one when they move much more (mocap.calibration.live); "
                         "the latest is also written to --out as a session")
    ca.add_argument("--publish", metavar="EP", help="--follow: where to publish (one of mocapd's inputs)")
    ca.add_argument("--duration", type=float, default=None, help="--follow: stop after this many seconds")
    ca.set_defaults(func=run)


def _follow(args: argparse.Namespace) -> int:
    if not (args.connect and args.session and args.publish):
        raise InputError("--follow needs --connect, --session and --publish")
    published = live.follow(args.connect, Path(args.session), Path(args.out), args.publish, args.seconds,
                            live.Policy(max_wait_s=args.max_seconds), duration_s=args.duration)
    print(json.dumps({"calibrations": [{k: c[k] for k in ("sequence", "valid_from_ns", "score_deg")}
                                       for c in published]}), flush=True)
    return 0


def run(args: argparse.Namespace) -> int:
    if bool(args.recording) == bool(args.connect):
        raise InputError("give exactly one of --recording FILE and --connect EP...")
    if args.follow:
        return _follow(args)
    recorded = Path(args.recording) if args.recording else Path(args.out) / "calibration.mcap"
    if args.connect:
        if not args.session:
            raise InputError("--connect needs --session: the rig, layout and IMU set to calibrate")
        recorded.parent.mkdir(parents=True, exist_ok=True)
        from_recording.record_window(args.connect, recorded, Path(args.session), args.seconds,
                                     max_seconds=args.max_seconds)
    report = from_recording.calibrate(recorded, Path(args.out), Path(args.session) if args.session else None,
                                      args.seconds, tuple(args.span) if args.span else None)
    print(json.dumps({"session": str(Path(args.out) / "session.json"), "frames": report["frames"],
                      "imus_calibrated": len(report["imus_calibrated"]), "imus_missing": report["imus_missing"],
                      "integrity": report["integrity"]}),
          flush=True)
    return 0
