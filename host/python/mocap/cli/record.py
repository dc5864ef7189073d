"""`mocap record --connect EP... --out FILE`: the streams of ZeroMQ publishers to an MCAP file."""

from __future__ import annotations

import argparse
import json
import signal
import threading

from mocap.recording import recorder


def register(sub: argparse._SubParsersAction) -> None:
    rec = sub.add_parser("record", help="record the streams of ZeroMQ publishers to an MCAP file (Foxglove)")
    rec.add_argument("--connect", nargs="+", required=True, metavar="EP", help="publisher endpoints, tcp://host:port")
    rec.add_argument("--out", required=True, help="MCAP file to write")
    rec.add_argument("--seconds", type=float, default=None, help="stop after this long (default: at Ctrl-C)")
    rec.add_argument("--session", default=None, help="attach this session file and the files it names "
                     "(then `mocap solve --recording` needs nothing else); its CURVE keys, if any, are used")
    rec.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):  # Ctrl-C, systemctl stop: the file is closed properly
        signal.signal(sig, lambda *_: stop.set())
    counts = recorder.record(args.connect, args.out, args.seconds, stop, session=args.session)
    print(json.dumps({"out": args.out, "recorded": counts.recorded, "dropped": counts.dropped}), flush=True)
    return 0
