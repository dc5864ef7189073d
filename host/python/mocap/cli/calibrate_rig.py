"""`mocap calibrate-rig --take DIR|--recording REC --height M --out Calib.toml`: the cameras'
poses from the person in view, without a board (mocap.calibration.rig)."""

from __future__ import annotations

import argparse
import json
import logging
import signal
import threading
from pathlib import Path

from mocap import _core
from mocap.calibration.rig import calibrate, compare, live, recorded
from mocap.errors import InputError
from mocap.io import calib_toml, take_folder

log = logging.getLogger(__name__)
LIVE_ONLY = {"seconds": 60.0, "every": 10.0, "record": None, "session": None}  # their defaults


def register(sub: argparse._SubParsersAction) -> None:
    c = sub.add_parser(
        "calibrate-rig", help="estimate the cameras' poses from a take's detections of the person in view (no board)",
        description="Estimates every camera's position and orientation from the 2D keypoints of one person (the "
        "most confident in each view) of a take folder, a recording of the camera boxes' streams, or the boxes "
        "live (refined as the person walks about): the essential matrix of the two cameras that share the most "
        "keypoints, the others by PnP, then a bundle adjustment (Cauchy loss, the detections' confidences). "
        "Metres from the person's stated height; Z up from the floor their still feet stand on (or their mean "
        "standing axis), the origin on the floor under them, X the way they face on average. The intrinsics "
        "(focal lengths, principal point, distortion) are the take's calibration file's (a recording's: its "
        "attached session's), --intrinsics' or a pinhole of --fov degrees; their extrinsics are ignored. Writes a Pose2Sim / anipose Calib.toml (Z-up world).")
    source = c.add_mutually_exclusive_group(required=True)
    source.add_argument("--take", help="take folder (docs/take_format.md)")
    source.add_argument("--recording", help="recording of the camera boxes' streams (`mocap record`): their "
                        "KeypointFrames, on common frames by capture time")
    source.add_argument("--connect", nargs="+", metavar="EP",
                        help="live: the camera boxes' endpoints; their streams recorded (--record) and the rig "
                        "estimated from all received so far every --every seconds, written over --out each time")
    c.add_argument("--seconds", type=float, default=LIVE_ONLY["seconds"], help="--connect: how long to listen (default 60)")
    c.add_argument("--every", type=float, default=LIVE_ONLY["every"], help="--connect: seconds between estimates (default 10)")
    c.add_argument("--record", default=None, metavar="FILE",
                   help="--connect: the recording of the streams (default: --out's name with .mcap)")
    c.add_argument("--session", default=None,
                   help="--connect: a session whose rig gives the intrinsics and whose CURVE keys, if any, are used "
                   "(attached to the recording)")
    c.add_argument("--height", required=True, type=float, help="the person's height, metres (sets the scale)")
    c.add_argument("--out", required=True, help="Calib.toml to write")
    c.add_argument("--intrinsics", default=None,
                   help="Calib.toml whose cameras (by the take's camera names) give the intrinsics (default: the "
                   "take's own calibration file; a recording's attached session)")
    c.add_argument("--fov", type=float, default=None, metavar="DEG",
                   help="no intrinsics known: a pinhole camera of this horizontal field of view (degrees) on the "
                   "image, its principal point at the centre, no distortion (an approximation: give the real "
                   "intrinsics when you have them)")
    c.add_argument("--report", default=None, help="also write the calibration report as JSON")
    c.add_argument("--compare", action="store_true",
                   help="also compare the estimate with the take's own calibration or the recording's session's (a "
                   "board's), after the similarity that best aligns the camera centres: per camera position (cm) "
                   "and orientation (deg), the scale, the up axes' angle (in the report and the printed line)")
    c.set_defaults(func=run)


def intrinsics(take: take_folder.TakeFolder, path: str | None, fov_deg: float | None) -> list:
    if path is None and fov_deg is not None:
        return [recorded.from_field_of_view(c.name, c.width, c.height, fov_deg) for c in take.rig.cameras]
    if path is None:
        return list(take.rig.cameras)
    given = {cam.name: cam for cam in calib_toml.load(path).cameras}
    missing = [cam.name for cam in take.rig.cameras if cam.name not in given]
    if missing:
        raise InputError(f"{path}: no camera named {missing[0]!r} (the take's cameras: "
                         f"{', '.join(c.name for c in take.rig.cameras)})")
    return [given[cam.name] for cam in take.rig.cameras]


def _from_take(args: argparse.Namespace) -> tuple:
    """The rig, its report, and the rig to compare it with (the take's own calibration)."""
    take = take_folder.read_take(Path(args.take))
    if take.rig is None:
        raise InputError(f"{args.take}: the take has no [video] table: no cameras to calibrate")
    rig, report = calibrate.calibrate(intrinsics(take, args.intrinsics, args.fov), take.people, take.layout,
                                      take.frame_rate, args.height)
    return rig, report, take.rig


def _from_recording(args: argparse.Namespace) -> tuple:
    """The rig, its report, and the rig to compare it with (the recording's session's)."""
    own_intrinsics = args.intrinsics is None and args.fov is None
    detections = recorded.read(Path(args.recording), with_session=args.compare or own_intrinsics)
    cameras = recorded.intrinsics(detections, args.intrinsics, args.fov)
    rig, report = calibrate.calibrate(cameras, detections.people, detections.layout, detections.rate, args.height)
    if not args.compare:
        return rig, report, None
    known = {c.name: c for c in detections.session_rig.cameras} if detections.session_rig is not None else {}
    if any(c not in known for c in detections.cameras):
        raise InputError(f"{args.recording}: --compare needs the recording's session with a rig of its cameras")
    return rig, report, _core.Rig([known[c] for c in detections.cameras])


def _live(args: argparse.Namespace) -> int:
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):  # Ctrl-C: the last estimate from what came
        signal.signal(sig, lambda *_: stop.set())
    out = Path(args.out)
    record = Path(args.record) if args.record else out.with_suffix(".mcap")
    live.run(args.connect, record, out, args.height,
             lambda detections: recorded.intrinsics(detections, args.intrinsics, args.fov),
             args.seconds, args.every, lambda line: print(json.dumps(line), flush=True),
             Path(args.session) if args.session else None, stop)
    return 0


def run(args: argparse.Namespace) -> int:
    if args.intrinsics is not None and args.fov is not None:
        raise InputError("give --intrinsics or --fov, not both")
    if args.connect:
        if args.compare or args.report:
            raise InputError("--compare and --report are for --take and --recording (calibrate the recording "
                             "--connect leaves, --record, with them)")
        return _live(args)
    live_only = [f"--{name}" for name in LIVE_ONLY if getattr(args, name) != LIVE_ONLY[name]]
    if live_only:
        raise InputError(f"{', '.join(live_only)}: for --connect only (a live calibration)")
    rig, report, reference = _from_take(args) if args.take else _from_recording(args)
    Path(args.out).write_text(calib_toml.dumps(rig))
    if args.compare:
        report["compared_with_the_takes_calibration"] = compare.compare(rig, reference)
    if args.report:
        Path(args.report).write_text(json.dumps(report, indent=1) + "\n")
    log.info("wrote %s (%d cameras, reprojection median %.2f px)", args.out, len(rig.cameras),
             report["reprojection_px_median"])
    line = {"out": args.out, "cameras": len(rig.cameras), "frames": report["frames"],
            "reprojection_px_median": round(report["reprojection_px_median"], 3), "up_from": report["up_from"]}
    if args.compare:
        line.update({k: round(v, 3) for k, v in report["compared_with_the_takes_calibration"].items()
                     if not isinstance(v, dict)})
    print(json.dumps(line), flush=True)
    return 0
