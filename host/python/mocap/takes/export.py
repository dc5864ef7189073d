"""A solve as files other tools open (`mocap export`, `mocap batch --export`): TRC for OpenSim
and Pose2Sim, C3D and CSV (the joint positions), binary glTF for animation tools and BVH (the
motion). A solve is `mocap solve --take`'s output folder, one of its files (a joint-position
CSV, a BVH), or a recording of a live take (MCAP with mocapd's poses: the poses as published,
not solved again). A recording of several people gives one file per person, OUT's name with
`_subjectN` before its suffix (N the subject id mocapd gave them), or the one person asked for."""

from __future__ import annotations

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
SUFFIXES = {"trc": ".trc", "c3d": ".c3d", "csv": ".csv", "gltf": ".glb", "bvh": ".bvh"}
MOTION_FORMATS = ("gltf", "bvh")  # from the motion (a BVH); the others from the joint positions
BVH_UNITS = {"cm": 0.01, "mm": 0.001, "m": 1.0}
MCAP_MAGIC = b"\x89MCAP0\r\n"


def is_recording(path: Path) -> bool:
    with open(path, "rb") as f:
        return f.read(len(MCAP_MAGIC)) == MCAP_MAGIC


def _from_recording(path: Path, fmt: str, folder: Path, subject: int | None) -> dict[int, Path]:
    """Per subject (0 alone; only `subject` when given), the recording's published poses as the
    file `fmt` is exported from (a BVH or a joint CSV), written in folder."""
    take = published.read(path)
    sources = {}
    for subject in take.subjects() if subject is None else [subject]:
        person = take.of(subject)
        name = folder / f"subject{subject}"
        if fmt in MOTION_FORMATS:
            if person.skeleton is None:
                raise InputError(f"{path}: no skeleton (no session attached, no calibration recorded): {fmt} needs one")
            write_bvh(name.with_suffix(".bvh"), person.skeleton, person.thetas(), person.rate_hz())
            sources[subject] = name.with_suffix(".bvh")
        else:
            names = [j.name for j in person.poses[0].joints]
            write_positions_csv(name.with_suffix(".csv"), names, person.positions(), person.times())
            sources[subject] = name.with_suffix(".csv")
    return sources


def source_files(solved: Path, fmt: str, folder: Path, subject: int | None = None) -> dict[int, Path]:
    """Per subject (0 alone; only `subject` when given), the BVH (motion formats) or joint CSV
    (the others) to export from; written into folder from a recording."""
    if solved.is_dir():
        solved = solved / ("take.bvh" if fmt in MOTION_FORMATS else "joints.csv")
    if not solved.is_file():
        raise InputError(f"{solved}: no such file (give a solved take folder, the file to export, or a recording)")
    if is_recording(solved):
        return _from_recording(solved, fmt, folder, subject)
    if (solved.suffix.lower() == ".bvh") != (fmt in MOTION_FORMATS):
        raise InputError(f"{solved}: {fmt} is exported from a " + ("BVH" if fmt in MOTION_FORMATS else "joint CSV"))
    return {0: solved}


def export(solved: Path, fmt: str, out: Path, bvh_units: str = "cm", subject: int | None = None) -> dict:
    """Writes `out` in format `fmt` from a solve (of several people: a file per person, or
    `subject`'s alone); what it holds and its convention."""
    with tempfile.TemporaryDirectory() as folder:
        sources = source_files(Path(solved), fmt, Path(folder), subject)
        if subject is not None:  # a take folder or file: the one person it holds
            if subject not in sources:
                raise InputError(f"{solved}: no subject {subject} (subjects: {', '.join(map(str, sources))})")
            sources = {subject: sources[subject]}
        targets = {s: out if len(sources) == 1 else published.subject_file(out, s) for s in sources}
        written = {}
        for s, source in sources.items():
            try:
                written[s] = _write(fmt, source, targets[s], bvh_units)
            except OSError as e:
                raise InputError(f"{targets[s]}: cannot write it: {e}") from None
    if len(written) == 1:
        return {**next(iter(written.values())), "convention": FORMATS[fmt]}
    return {"subjects": {str(s): {"out": str(targets[s]), **w} for s, w in written.items()}, "convention": FORMATS[fmt]}


def _write(fmt: str, source: Path, out: Path, bvh_units: str) -> dict:
    """Writes out from source; what it holds."""
    if fmt in MOTION_FORMATS:
        motion = bvh.load(source)
        if fmt == "gltf":
            write_glb(out, motion, BVH_UNITS[bvh_units])
        elif Path(source).resolve() != Path(out).resolve():
            shutil.copyfile(source, out)
        return {"frames": motion.num_frames, "joints": len(motion.joints), "rate_hz": round(1 / motion.frame_time, 3)}
    names, positions, times = read_positions_csv(source)
    # the times are written to the microsecond: the rate to the millihertz (59.94 stays)
    rate = round((len(times) - 1) / float(times[-1] - times[0]), 3) if len(times) > 1 else 1.0
    if fmt == "trc":
        write_trc(out, [POSE2SIM_MARKERS.get(n, n) for n in names], positions @ retarget.P, rate, times)
    elif fmt == "c3d":
        write_c3d(out, names, positions, rate)
    else:
        write_positions_csv(out, names, positions, times)
    return {"frames": len(times), "markers": len(names), "rate_hz": rate}
