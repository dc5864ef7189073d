"""`mocap export SOLVED --format trc|c3d|gltf|bvh|csv --out FILE`: a solve as files other tools
open: TRC for OpenSim and Pose2Sim, C3D and CSV (the joint positions), binary glTF for animation
tools and BVH (the motion). SOLVED is `mocap solve --take`'s output folder, one of its files (a
joint-position CSV, a BVH), or a recording of a live take (MCAP with mocapd's poses: the poses
as published, not solved again)."""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
from pathlib import Path

from mocap.errors import InputError
from mocap.io import bvh, retarget
from mocap.io.bvh_export import write_bvh
from mocap.io.c3d_export import write_c3d
from mocap.io.gltf_export import write_glb
from mocap.io.joints_csv import read_positions_csv, write_positions_csv
from mocap.io.trc import POSE2SIM_MARKERS, write_trc
from mocap.recording import published

FORMATS = {
    # Pose2Sim's convention, which its OpenSim models expect: Y up (v = P^T v_world, as its
    # TRC is read: mocap.io.retarget.P), metres, its marker names for the joint centres
    "trc": "Y up (OpenSim), metres; joint centres named as Pose2Sim's markers",
    # C3D's usual frame (Vicon, Visual3D): Z up as ours, millimetres
    "c3d": "Z up, millimetres; names as in the CSV",
    "csv": "Z up, metres; a joint's x, y, z per column (mocap.io.joints_csv)",
    # glTF's frame is the BVH's (Y up, facing +Z), mocap.io.gltf_export
    "gltf": "binary glTF 2.0: Y up, metres; a skinned skeleton and its animation",
    "bvh": "Y up, facing +Z, centimetres (mocap.io.bvh_export)",
}
MOTION_FORMATS = ("gltf", "bvh")  # from the motion (a BVH); the others from the joint positions
BVH_UNITS = {"cm": 0.01, "mm": 0.001, "m": 1.0}
MCAP_MAGIC = b"\x89MCAP0\r\n"


def register(sub: argparse._SubParsersAction) -> None:
    ex = sub.add_parser("export", help="write a solve as TRC (OpenSim, Pose2Sim), C3D, CSV, binary glTF or BVH")
    ex.add_argument("solved", help="`mocap solve --take`'s output folder; its joint-position CSV (trc, c3d, csv) "
                    "or BVH (gltf, bvh); or a recording of a live take with mocapd's poses (.mcap: every format)")
    ex.add_argument("--format", required=True, choices=sorted(FORMATS),
                    help="; ".join(f"{k}: {v}" for k, v in FORMATS.items()))
    ex.add_argument("--out", required=True, help="the file to write (gltf: a .glb)")
    ex.add_argument("--bvh-units", choices=sorted(BVH_UNITS), default="cm",
                    help="gltf from a BVH: its length unit (default cm, as `mocap solve` writes)")
    ex.set_defaults(func=run)


def _is_recording(path: Path) -> bool:
    with open(path, "rb") as f:
        return f.read(len(MCAP_MAGIC)) == MCAP_MAGIC


def _from_recording(path: Path, fmt: str, folder: Path) -> Path:
    """The recording's published poses as the file `fmt` is exported from (a BVH or a joint CSV) in folder."""
    take = published.read(path)
    if fmt in MOTION_FORMATS:
        if take.skeleton is None:
            raise InputError(f"{path}: no skeleton (no session attached, no calibration recorded): {fmt} needs one")
        write_bvh(folder / "take.bvh", take.skeleton, take.thetas(), take.rate_hz())
        return folder / "take.bvh"
    write_positions_csv(folder / "joints.csv", [j.name for j in take.poses[0].joints], take.positions(), take.times())
    return folder / "joints.csv"


def source_file(solved: Path, fmt: str, folder: Path) -> Path:
    """The BVH (motion formats) or joint CSV (the others) to export from; written into folder
    from a recording."""
    if solved.is_dir():
        solved = solved / ("take.bvh" if fmt in MOTION_FORMATS else "joints.csv")
    if not solved.is_file():
        raise InputError(f"{solved}: no such file (give a solved take folder, the file to export, or a recording)")
    if _is_recording(solved):
        return _from_recording(solved, fmt, folder)
    if (solved.suffix.lower() == ".bvh") != (fmt in MOTION_FORMATS):
        raise InputError(f"{solved}: {fmt} is exported from a " + ("BVH" if fmt in MOTION_FORMATS else "joint CSV"))
    return solved


def run(args: argparse.Namespace) -> int:
    with tempfile.TemporaryDirectory() as folder:
        source = source_file(Path(args.solved), args.format, Path(folder))
        try:
            summary = _write(args, source)
        except OSError as e:
            raise InputError(f"{args.out}: cannot write it: {e}") from None
    print(json.dumps({"out": args.out, "format": args.format, **summary, "convention": FORMATS[args.format]}),
          flush=True)
    return 0


def _write(args: argparse.Namespace, source: Path) -> dict:
    """Writes args.out from source; what it holds."""
    if args.format in MOTION_FORMATS:
        motion = bvh.load(source)
        if args.format == "gltf":
            write_glb(args.out, motion, BVH_UNITS[args.bvh_units])
        else:
            shutil.copyfile(source, args.out)
        return {"frames": motion.num_frames, "joints": len(motion.joints), "rate_hz": round(1 / motion.frame_time, 3)}
    names, positions, times = read_positions_csv(source)
    # the times are written to the microsecond: the rate to the millihertz (59.94 stays)
    rate = round((len(times) - 1) / float(times[-1] - times[0]), 3) if len(times) > 1 else 1.0
    if args.format == "trc":
        write_trc(args.out, [POSE2SIM_MARKERS.get(n, n) for n in names], positions @ retarget.P, rate, times)
    elif args.format == "c3d":
        write_c3d(args.out, names, positions, rate)
    else:
        write_positions_csv(args.out, names, positions, times)
    return {"frames": len(times), "markers": len(names), "rate_hz": rate}
