"""`mocap calibrate-rig --take DIR --height M --out Calib.toml`: the cameras' poses from the
person in view, without a board (mocap.calibration.rig)."""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

from mocap.calibration.rig import calibrate, compare
from mocap.errors import InputError
from mocap.io import calib_toml, take_folder

log = logging.getLogger(__name__)


def register(sub: argparse._SubParsersAction) -> None:
    c = sub.add_parser(
        "calibrate-rig", help="estimate the cameras' poses from a take's detections of the person in view (no board)",
        description="Estimates every camera's position and orientation from a take folder's 2D keypoints of one "
        "person (the most confident in each view): the essential matrix of the two cameras that share the most "
        "keypoints, the others by PnP, then a bundle adjustment (Cauchy loss, the detections' confidences). "
        "Metres from the person's stated height; Z up from the floor their still feet stand on (or their mean "
        "standing axis), the origin on the floor under them, X the way they face on average. The intrinsics "
        "(focal lengths, principal point, distortion) are the take's calibration file's or --intrinsics'; "
        "their extrinsics are ignored. Writes a Pose2Sim / anipose Calib.toml (Z-up world).")
    c.add_argument("--take", required=True, help="take folder (docs/take_format.md)")
    c.add_argument("--height", required=True, type=float, help="the person's height, metres (sets the scale)")
    c.add_argument("--out", required=True, help="Calib.toml to write")
    c.add_argument("--intrinsics", default=None,
                   help="Calib.toml whose cameras (by the take's camera names) give the intrinsics (default: the "
                   "take's own calibration file)")
    c.add_argument("--report", default=None, help="also write the calibration report as JSON")
    c.add_argument("--compare", action="store_true",
                   help="also compare the estimate with the take's own calibration (a board's), after the similarity "
                   "that best aligns the camera centres: per camera position (cm) and orientation (deg), the scale, "
                   "the up axes' angle (in the report and the printed line)")
    c.set_defaults(func=run)


def intrinsics(take: take_folder.TakeFolder, path: str | None) -> list:
    if path is None:
        return list(take.rig.cameras)
    given = {cam.name: cam for cam in calib_toml.load(path).cameras}
    missing = [cam.name for cam in take.rig.cameras if cam.name not in given]
    if missing:
        raise InputError(f"{path}: no camera named {missing[0]!r} (the take's cameras: "
                         f"{', '.join(c.name for c in take.rig.cameras)})")
    return [given[cam.name] for cam in take.rig.cameras]


def run(args: argparse.Namespace) -> int:
    take = take_folder.read_take(Path(args.take))
    if take.rig is None:
        raise InputError(f"{args.take}: the take has no [video] table: no cameras to calibrate")
    rig, report = calibrate.calibrate(intrinsics(take, args.intrinsics), take.people, take.layout, take.frame_rate,
                                      args.height)
    Path(args.out).write_text(calib_toml.dumps(rig))
    if args.compare:
        report["compared_with_the_takes_calibration"] = compare.compare(rig, take.rig)
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
