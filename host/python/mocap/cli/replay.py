"""`mocap replay FILE --bind EP`: a recording's messages published on ZeroMQ."""

from __future__ import annotations

import argparse
import json

from mocap.net import keys
from mocap.net.keys import ServerKeys
from mocap.recording import reader, replay


def register(sub: argparse._SubParsersAction) -> None:
    rep = sub.add_parser("replay", help="publish a recording's messages on ZeroMQ, following their log times")
    rep.add_argument("file", help="MCAP file made by `mocap record`")
    rep.add_argument("--bind", required=True, metavar="EP", help="endpoint to publish on, tcp://*:port")
    pace = rep.add_mutually_exclusive_group()
    pace.add_argument("--speed", type=float, default=1.0, help="times real time (default 1)")
    pace.add_argument("--max-speed", action="store_true", help="as fast as the subscribers take the messages")
    rep.add_argument("--restamp", action="store_true", help="move the recorded times to now, so that a live host "
                     "(mocapd) takes the replay for a take happening now")
    rep.add_argument("--topics", nargs="+", default=None, metavar="PATTERN",
                     help="topic patterns to send (default: the inputs, /camera/* /imu/* /calibration/*)")
    rep.add_argument("--curve-secret", metavar="FILE", help="publish as a CURVE server with this secret key "
                     "(`mocap keys`; the session of the mocapd it feeds lists its public key for the endpoint)")
    rep.set_defaults(func=run)


def _keys(secret: str | None) -> ServerKeys | None:
    return None if secret is None else ServerKeys(keys.read_secret(secret))


def run(args: argparse.Namespace) -> int:
    with reader.Recording(args.file) as recording:
        sent = replay.replay(recording, args.bind, None if args.max_speed else args.speed, args.topics,
                             restamp=args.restamp, keys=_keys(args.curve_secret))
    print(json.dumps({"file": args.file, "sent": sent, "integrity": recording.integrity.as_dict()}), flush=True)
    return 0
