"""`mocap export SOLVED --format trc|c3d|gltf --out FILE`: a solve as files other tools open:
TRC for OpenSim and Pose2Sim and C3D (the joint positions: `mocap solve --take`'s joints.csv,
or `mocap solve --recording --csv`'s CSV), binary glTF for animation tools (the motion: a BVH
of `mocap solve`). SOLVED is `mocap solve --take`'s output folder or the file itself."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mocap.errors import InputError
from mocap.io import bvh, retarget
from mocap.io.c3d_export import write_c3d
from mocap.io.gltf_export import write_glb
from mocap.io.joints_csv import read_positions_csv
from mocap.io.trc import POSE2SIM_MARKERS, write_trc

FORMATS = {
    # Pose2Sim's convention, which its OpenSim models expect: Y up (v = P^T v_world, as its
    # TRC is read: mocap.io.retarget.P), metres, its marker names for the joint centres
    "trc": "Y up (OpenSim), metres; joint centres named as Pose2Sim's markers",
    # C3D's usual frame (Vicon, Visual3D): Z up as ours, millimetres
    "c3d": "Z up, millimetres; names as in the CSV",
    # glTF's frame is the BVH's (Y up, facing +Z), mocap.io.gltf_export
    "gltf": "binary glTF 2.0: Y up, metres; a skinned skeleton and its animation",
}
SOURCE = {"trc": "joints.csv", "c3d": "joints.csv", "gltf": "take.bvh"}  # in a solved take folder
BVH_UNITS = {"cm": 0.01, "mm": 0.001, "m": 1.0}


def register(sub: argparse._SubParsersAction) -> None:
    ex = sub.add_parser("export", help="write a solve as TRC (OpenSim, Pose2Sim), C3D or binary glTF")
    ex.add_argument("solved", help="`mocap solve --take`'s output folder, or its file: a joint-position CSV (trc, "
                    "c3d) or a BVH (gltf)")
    ex.add_argument("--format", required=True, choices=sorted(FORMATS),
                    help="; ".join(f"{k}: {v}" for k, v in FORMATS.items()))
    ex.add_argument("--out", required=True, help="the file to write (gltf: a .glb)")
    ex.add_argument("--bvh-units", choices=sorted(BVH_UNITS), default="cm",
                    help="gltf: the BVH's length unit (default cm, as `mocap solve` writes)")
    ex.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    source = Path(args.solved)
    if source.is_dir():
        source = source / SOURCE[args.format]
    if not source.is_file():
        raise InputError(f"{source}: no such file (give a solved take folder or the file to export)")
    try:
        summary = _write(args, source)
    except OSError as e:
        raise InputError(f"{args.out}: cannot write it: {e}") from None
    print(json.dumps({"out": args.out, "format": args.format, **summary, "convention": FORMATS[args.format]}),
          flush=True)
    return 0


def _write(args: argparse.Namespace, source: Path) -> dict:
    """Writes args.out from source; what it holds."""
    if args.format == "gltf":
        motion = bvh.load(source)
        write_glb(args.out, motion, BVH_UNITS[args.bvh_units])
        return {"frames": motion.num_frames, "joints": len(motion.joints), "rate_hz": round(1 / motion.frame_time, 3)}
    names, positions, times = read_positions_csv(source)
    # the times are written to the microsecond: the rate to the millihertz (59.94 stays)
    rate = round((len(times) - 1) / float(times[-1] - times[0]), 3) if len(times) > 1 else 1.0
    if args.format == "trc":
        write_trc(args.out, [POSE2SIM_MARKERS.get(n, n) for n in names], positions @ retarget.P, rate, times)
    else:
        write_c3d(args.out, names, positions, rate)
    return {"frames": len(times), "markers": len(names), "rate_hz": rate}
