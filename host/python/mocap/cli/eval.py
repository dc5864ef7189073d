"""`mocap eval`: simulated takes of real motion solved and scored (or the paper's tables)."""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

from mocap import paths
from mocap.errors import InputError
from mocap.eval import floors, people, real_people, simulated, tables, tables_heading, take_truth
from mocap.sim import detector, extremes, take

PRESETS = ["hq13", "hs13", "hq6", "hs6"]


def register(sub: argparse._SubParsersAction) -> None:
    e = sub.add_parser("eval", help="simulate takes of real motion, solve them and score the solver")
    e.add_argument("--motion", action="append", default=[],
                   help="BVH file or folder of BVH files (searched recursively); repeatable")
    e.add_argument("--people", type=int, default=None, metavar="N",
                   help="instead: one scene of N performers playing the --motion clips (in turn; a clip used "
                        "again starts elsewhere in it), tracked and solved together from video (--seconds long, "
                        "default 8), each also solved alone; identity swaps and errors per performer to --json")
    e.add_argument("--multiperson-trial", action="store_true",
                   help="instead: Pose2Sim's real multi-person trial (Demo_MultiPerson, fetched on first use) "
                        "detected by the camera box's detector, tracked and solved from video; figures to --json")
    e.add_argument("--floors", action="store_true",
                   help="instead: what each bone's measurements allow, beside the solve's error per bone: a "
                        "sensor's own error; for a bone without one, its orientation fitted to one frame's "
                        "detections with every other bone at the truth (mocap.eval.floors); to --json")
    e.add_argument("--sheet", metavar="JPG", help="--multiperson-trial: a contact sheet of frames with the ids drawn")
    e.add_argument("--no-suits", action="store_true", help="--people: video only (default: each wears a suit of "
                   "13 IMUs calibrated on them, which the tracker finds on them from motion)")
    e.add_argument("--swap-suits-at", type=float, default=None, metavar="S",
                   help="--people: performers 1 and 2 swap suits S seconds into the scene")
    e.add_argument("--take", metavar="DIR",
                   help="instead: a take folder of `mocap simulate`, solved as `mocap solve --take` solves it "
                        "(into --out) and scored against the truth beside it")
    e.add_argument("--out", metavar="DIR", help="--take: where the solve writes (default: DIR/solved)")
    e.add_argument("--preset", default="hq13", choices=PRESETS,
                   help="HQ: detections every frame, 8 cameras; HS: 2 of every 8 frames, 4 cameras (default hq13)")
    e.add_argument("--cameras", type=int, default=None, help="number of cameras (default: the preset's)")
    e.add_argument("--omit", nargs="*", default=[], choices=list(simulated.TERMS), help="cost terms to switch off")
    e.add_argument("--site-offsets", default="on", choices=["on", "off"],
                   help="the detector's systematic 1-3 cm site offsets (default on)")
    e.add_argument("--seed", type=int, default=0, help="random seed of the simulation (default 0)")
    e.add_argument("--baseline", default=None, choices=["imu-only", "triangulation"],
                   help="score a baseline instead of the fused solver: IMU-only FK, or real-time robust "
                        "triangulation + swap fix + one-euro smoothing + bone-length fit")
    e.add_argument("--set", action="append", default=[], metavar="OPTION=VALUE",
                   help="a solver option, e.g. acceleration.weight=0.01 (repeatable)")
    e.add_argument("--calibration", default="estimated", choices=["estimated", "oracle"],
                   help="estimated: skeleton, keypoint sites, IMU mounting and heading from the take's first 5 s "
                        "with motion (mocap.calibration.window); oracle: the true ones (default estimated)")
    e.add_argument("--site-std", type=float, default=None, metavar="MM",
                   help="estimated calibration: keep the keypoint sites' change along directions known within "
                        "this many mm (default 2; 0: keep the layout's sites)")
    e.add_argument("--bend", action="append", default=[], metavar="BONE[,BONE]:AXIS:DEG",
                   help="bend bones beyond the clip from 1 s on (their own axis x|y|z), e.g. foot_l,foot_r:x:90")
    e.add_argument("--slip", action="append", default=[], metavar="SENSOR:AT_S:AXIS:DEG",
                   help="a sensor slips on its segment at AT_S (its own axis), e.g. forearm_l:4:z:60")
    e.add_argument("--cameras-lost-at", type=float, default=None, metavar="S",
                   help="every camera stops detecting S seconds into the take (IMUs only from then on); "
                        "the JSON gets the joints' error 0.5, 1, 2 and 4 s later")
    e.add_argument("--json", help="JSON file to write the results to")
    e.add_argument("--table", choices=["paper", "heading"],
                   help="paper: regenerate the paper's tables and plots on the test clips; heading: print the "
                        "heading tracking's table (a long take of the demo motion, --seconds)")
    e.add_argument("--seconds", type=float, default=None,
                   help="length of the --table heading take (default 60) or of the --people scene (default 8)")
    e.add_argument("--docs", default=str(paths.REPO / "docs"), help="where --table writes results.md (default docs/)")
    e.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if args.table == "heading":
        seconds = args.seconds or 60.0
        print(tables_heading.markdown(tables_heading.rows(seconds), seconds), end="", flush=True)
        return 0
    if args.table:
        summary = tables.write(args.seed, Path(args.docs), f"mocap eval --table paper --seed {args.seed}")
        print(json.dumps({p: round(s["pos_error_cm"], 2) for p, s in summary["configurations"].items()}), flush=True)
        return 0
    if args.take:
        return _take(args)
    if args.multiperson_trial:
        result = real_people.evaluate(Path(args.sheet) if args.sheet else None)
        if args.json:
            Path(args.json).write_text(json.dumps(result, indent=1) + "\n")
        print(json.dumps({k: v for k, v in result.items() if k != "tracker"}), flush=True)
        return 0
    if not args.motion or not args.json:
        raise InputError("--motion (or --take) and --json are needed unless --table is given")
    clips = [c for m in map(Path, args.motion) for c in (sorted(m.rglob("*.bvh")) if m.is_dir() else [m])]
    missing = [str(c) for c in clips if not c.is_file()]
    if missing or not clips:
        raise InputError(f"no such BVH file: {', '.join(missing) or ' '.join(args.motion)}")
    if args.people is not None:
        return _people(args, clips)
    if args.floors:
        return _floors(args, clips)
    bends, slips = tuple(map(extremes.Bend.parse, args.bend)), tuple(map(extremes.Slip.parse, args.slip))
    config = take.Config(preset=args.preset, cameras=args.cameras,
                         detector=dataclasses.replace(detector.DetectorErrors(), site_offsets=args.site_offsets == "on"),
                         bends=bends, slips=slips, cameras_lost_at_s=args.cameras_lost_at)
    cal_options = {} if args.site_std is None else {"site_std": args.site_std / 1000.0}
    results = [simulated.evaluate(clip, config, args.omit, args.seed, args.set, args.baseline, args.calibration,
                                  cal_options)
               for clip in clips]
    summary = simulated.summarise(results)
    Path(args.json).write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps({k: v for k, v in summary.items() if not isinstance(v, (list, dict))}), flush=True)
    for r in results:
        told = {k: r[k] for k in ("extremes", "distrusted", "upside_down_frames", "cameras_lost") if r.get(k)}
        if told:
            print(json.dumps({"clip": r["clip"], **told}), flush=True)
    return 0


def _floors(args: argparse.Namespace, clips: list[Path]) -> int:
    other = {"--bend": args.bend, "--slip": args.slip, "--site-offsets off": args.site_offsets == "off",
             "--omit": args.omit, "--baseline": args.baseline, "--cameras-lost-at": args.cameras_lost_at is not None}
    given = [name for name, value in other.items() if value]
    if given:  # the floors are of the simulation as it is; these would change only the solve
        raise InputError(f"--floors takes --preset, --cameras, --seed and --set, not {', '.join(given)}")
    config = take.Config(preset=args.preset, cameras=args.cameras)
    results = []
    for clip in clips:
        r = floors.evaluate(clip, config, args.seed)
        solved = simulated.evaluate(clip, config, [], args.seed, args.set, calibration="oracle")
        r["solve_deg"] = {b: e["ori_deg"] for b, e in solved["per_joint"].items()}
        results.append(r)
        print(json.dumps({"clip": str(clip), "solve_deg": round(solved["ori_error_deg"], 2),
                          "floors_deg": {b: round(f["floor_deg"], 1) for b, f in r["floors"].items()},
                          "sensors_deg": {b: round(e, 1) for b, e in r["sensors_deg"].items()}}), flush=True)
    Path(args.json).write_text(json.dumps(results, indent=1) + "\n")
    return 0


def _take(args: argparse.Namespace) -> int:
    folder = Path(args.take)
    result = take_truth.score(folder, Path(args.out) if args.out else folder / "solved")
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps({k: v for k, v in result.items() if k != "per_bone"}), flush=True)
    return 0


def _people(args: argparse.Namespace, clips: list[Path]) -> int:
    if args.people < 1 or args.people > 8:
        raise InputError(f"--people must be 1 to 8, not {args.people}")
    if args.swap_suits_at is not None and (args.people < 2 or args.no_suits or not args.swap_suits_at >= 0):
        raise InputError("--swap-suits-at needs two or more people in suits and a time >= 0")
    config = take.Config(preset=args.preset, cameras=args.cameras,
                         detector=dataclasses.replace(detector.DetectorErrors(), site_offsets=args.site_offsets == "on"))
    result = people.evaluate(clips, args.people, args.seconds or 8.0, config, args.seed, suits=not args.no_suits,
                             swap_suits_at_s=args.swap_suits_at)
    Path(args.json).write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps({k: v for k, v in result.items() if k not in ("performers", "tracker")}), flush=True)
    for r in result["performers"]:
        print(json.dumps(r), flush=True)
    return 0
