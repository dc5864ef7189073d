"""`mocap keys --out DIR --name DEVICE`: a device's CURVE key pair (README, "Securing the streams")."""

from __future__ import annotations

import argparse
import json

from mocap.net import keys


def register(sub: argparse._SubParsersAction) -> None:
    k = sub.add_parser("keys", help="make a device's CURVE key pair: DIR/DEVICE.key (secret, mode 0600) and "
                       "DIR/DEVICE.pub (public, for the session and the boxes' --curve-allow)")
    k.add_argument("--out", required=True, metavar="DIR", help="folder to write the two files into")
    k.add_argument("--name", required=True, metavar="DEVICE", help="the device: host, cam_01, hub0, calibrator...")
    k.add_argument("--force", action="store_true", help="replace an existing key pair of this name")
    k.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    secret, public = keys.make_keypair(args.out, args.name, args.force)
    print(json.dumps({"secret": str(secret), "public": str(public), "public_key": public.read_text().strip()}),
          flush=True)
    return 0
