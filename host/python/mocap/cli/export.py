"""`mocap export SOLVED --format trc|c3d --out FILE`: the joint positions of a solve (`mocap solve
--take`'s folder or its joints.csv, or `mocap solve --recording --csv`'s CSV) as a file that
biomechanics tools open: TRC for OpenSim and Pose2Sim, C3D."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mocap.errors import InputError
from mocap.io import retarget
from mocap.io.c3d_export import write_c3d
from mocap.io.joints_csv import read_positions_csv
from mocap.io.trc import POSE2SIM_MARKERS, write_trc

FORMATS = {
    # Pose2Sim's convention, which its OpenSim models expect: Y up (v = P^T v_world, as its
    # TRC is read: mocap.io.retarget.P), metres, its marker names for the joint centres
    "trc": "Y up (OpenSim), metres; joint centres named as Pose2Sim's markers",
    # C3D's usual frame (Vicon, Visual3D): Z up as ours, millimetres
    "c3d": "Z up, millimetres; names as in the CSV",
}


def register(sub: argparse._SubParsersAction) -> None:
    ex = sub.add_parser("export", help="write a solve's joint positions as TRC (OpenSim, Pose2Sim) or C3D")
    ex.add_argument("solved", help="`mocap solve --take`'s output folder, or a joint-position CSV of `mocap solve`")
    ex.add_argument("--format", required=True, choices=sorted(FORMATS),
                    help="; ".join(f"{k}: {v}" for k, v in FORMATS.items()))
    ex.add_argument("--out", required=True, help="the file to write")
    ex.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    source = Path(args.solved)
    if source.is_dir():
        source = source / "joints.csv"
    if not source.is_file():
        raise InputError(f"{source}: no such file (give a solved take folder or a joint-position CSV)")
    names, positions, times = read_positions_csv(source)
    # the times are written to the microsecond: the rate to the millihertz (59.94 stays)
    rate = round((len(times) - 1) / float(times[-1] - times[0]), 3) if len(times) > 1 else 1.0
    try:
        if args.format == "trc":
            write_trc(args.out, [POSE2SIM_MARKERS.get(n, n) for n in names], positions @ retarget.P, rate, times)
        else:
            write_c3d(args.out, names, positions, rate)
    except OSError as e:
        raise InputError(f"{args.out}: cannot write it: {e}") from None
    print(json.dumps({"out": args.out, "format": args.format, "frames": len(times), "markers": len(names),
                      "rate_hz": round(rate, 6), "convention": FORMATS[args.format]}), flush=True)
    return 0
