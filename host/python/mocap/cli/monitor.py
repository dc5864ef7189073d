"""`mocap monitor --connect EP`: the live view and status page of a running mocapd."""

from __future__ import annotations

import argparse
import asyncio
import sys
from pathlib import Path

import zmq

from mocap.errors import InputError
from mocap.io.session import Session
from mocap.monitor import scene
from mocap.monitor.server import Monitor

DEFAULT_HTTP = "127.0.0.1:8080"


def register(sub: argparse._SubParsersAction) -> None:
    m = sub.add_parser("monitor", help="serve a browser page showing a running mocapd's skeletons in 3D (every performer), the "
                       "cameras and every stream's health, live")
    m.add_argument("--connect", nargs="+", metavar="EP",
                   help="mocapd's output endpoint(s) (default: the session's `output`)")
    m.add_argument("--session", metavar="FILE", help="the session mocapd runs: its rig (the cameras drawn), "
                   "skeleton (the bones) and keys (to subscribe with CURVE); without it the default skeleton")
    m.add_argument("--http", default=DEFAULT_HTTP, metavar="[HOST:]PORT",
                   help=f"where the page is served (default {DEFAULT_HTTP}: this machine only; 0.0.0.0:PORT "
                        "shows it to the network — read-only); port 0: any free port")
    m.add_argument("--duration", type=float, default=None, metavar="S", help="stop after S seconds")
    m.set_defaults(func=run)


def http_address(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    try:
        number = int(port)
    except ValueError:
        number = -1
    if not 0 <= number <= 65535:
        raise InputError(f"--http {text}: expected [HOST:]PORT with a port 0..65535")
    return host.strip("[]") or "127.0.0.1", number


def run(args: argparse.Namespace) -> int:
    host, port = http_address(args.http)
    if args.duration is not None and not args.duration > 0:
        raise InputError(f"--duration {args.duration}: expected a positive number of seconds")
    session = Session.load(args.session) if args.session else None
    connect = args.connect or ([session.output.replace("*", "localhost")] if session else None)
    if not connect:
        raise InputError("--connect EP or --session FILE is needed: where mocapd publishes")
    page = scene.scene(Path(args.session) if args.session else None)
    monitor = Monitor(connect, page, keys=session.client_keys() if session else None)

    def ready(url: str) -> None:
        print(f"mocap monitor: {url}", flush=True)
    try:
        asyncio.run(monitor.run(host, port, ready, args.duration))
    except KeyboardInterrupt:
        pass
    except OSError as e:  # the port is taken, or the address is not this machine's
        print(f"mocap monitor: --http {args.http}: {e.strerror or e}", file=sys.stderr)
        return 2
    except zmq.ZMQError as e:  # an endpoint ZeroMQ cannot connect to
        print(f"mocap monitor: --connect {' '.join(connect)}: {e}", file=sys.stderr)
        return 2
    return 0
