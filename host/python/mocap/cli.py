"""The `mocap` command: one entry point for every part of the system."""

from __future__ import annotations

import argparse
import json
import logging
import sys

from mocap import paths
from mocap.errors import DataMissingError, InputError, MocapError
from mocap_edge.errors import EdgeError


def _bench(args: argparse.Namespace) -> int:
    from mocap import bench

    if "live" in args.only:  # before pinning: the edge processes and mocapd get the whole machine
        from mocap import live

        print(json.dumps(live.bench(seconds=args.live_seconds)), flush=True)
    if "edge" in args.only:
        from mocap.demo_data import fetch_trial
        from mocap_edge.detect import evaluation

        try:
            print(json.dumps(evaluation.bench(fetch_trial())), flush=True)
        except DataMissingError as e:
            print(json.dumps({"bench": "edge", "skipped": str(e)}), flush=True)
    if "firmware" in args.only:
        from mocap.imu_node import bench as firmware_bench

        print(json.dumps(firmware_bench.firmware()), flush=True)
    bench.pin_to_one_core()
    if "solver" in args.only:
        try:
            result = bench.solver(rate=args.rate, seed=args.seed, repeats=args.repeats, settings=args.set)
            print(json.dumps(result), flush=True)
        except DataMissingError as e:
            print(json.dumps({"bench": "solver", "skipped": str(e)}), flush=True)
    return 0


def _skeleton(args: argparse.Namespace) -> int:
    from mocap import _core, bvh, retarget

    motion = bvh.load(args.from_bvh)
    mapping = retarget.map_joints(motion, "auto" if args.scale == "auto" else float(args.scale))
    skeleton = _core.Skeleton.from_bones(retarget.BONES, mapping.parents, mapping.offsets)
    with open(args.out, "w") as f:
        f.write(skeleton.to_json() + "\n")
    logging.info("wrote %s (units scale %.6g, rest height %.3f m)", args.out, mapping.scale, skeleton.rest_height())
    return 0


def _rig(args: argparse.Namespace) -> int:
    from mocap import calib_toml

    rig = calib_toml.load(args.from_calib_toml)
    with open(args.out, "w") as f:
        f.write(rig.to_json() + "\n")
    logging.info("wrote %s (%d cameras)", args.out, len(rig.cameras))
    return 0


def _record(args: argparse.Namespace) -> int:
    import signal
    import threading

    from mocap import recording

    stop = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: stop.set())  # Ctrl-C ends the recording cleanly
    counts = recording.record(args.connect, args.out, args.seconds, stop, session=args.session)
    print(json.dumps({"out": args.out, "recorded": counts.recorded, "dropped": counts.dropped}), flush=True)
    return 0


def _replay(args: argparse.Namespace) -> int:
    from mocap import recording

    sent = recording.replay(args.file, args.bind, None if args.max_speed else args.speed, args.topics,
                            restamp=args.restamp)
    print(json.dumps({"file": args.file, "sent": sent}), flush=True)
    return 0


def _demo(args: argparse.Namespace) -> int:
    from pathlib import Path

    from mocap import demo

    result = demo.run(Path(args.out), args.seconds, vmc=args.vmc, seed=args.seed, record=args.record,
                      calibration=args.calibration, still_s=args.still_start)
    return 0 if result["solved"] else 1


def _calibrate(args: argparse.Namespace) -> int:
    from pathlib import Path

    from mocap import calibrate

    if bool(args.recording) == bool(args.connect):
        raise InputError("give exactly one of --recording FILE and --connect EP...")
    if args.follow:
        from mocap import calibrator

        if not (args.connect and args.session and args.publish):
            raise InputError("--follow needs --connect, --session and --publish")
        published = calibrator.follow(args.connect, Path(args.session), Path(args.out), args.publish, args.seconds,
                                      calibrator.Policy(max_wait_s=args.max_seconds), duration_s=args.duration)
        print(json.dumps({"calibrations": [{k: c[k] for k in ("sequence", "valid_from_ns", "score_deg")}
                                           for c in published]}), flush=True)
        return 0
    recorded = Path(args.recording) if args.recording else Path(args.out) / "calibration.mcap"
    if args.connect:
        if not args.session:
            raise InputError("--connect needs --session: the rig, layout and IMU set to calibrate")
        recorded.parent.mkdir(parents=True, exist_ok=True)
        calibrate.record_window(args.connect, recorded, Path(args.session), args.seconds,
                                max_seconds=args.max_seconds)
    report = calibrate.calibrate(recorded, Path(args.out), Path(args.session) if args.session else None,
                                 args.seconds)
    print(json.dumps({"session": str(Path(args.out) / "session.json"), "frames": report["frames"],
                      "imus_calibrated": len(report["imus_calibrated"]), "imus_missing": report["imus_missing"]}),
          flush=True)
    return 0


def _solve(args: argparse.Namespace) -> int:
    from pathlib import Path

    if bool(args.recording) == bool(args.take):
        raise InputError("give exactly one of --recording FILE and --take DIR")
    if args.take:
        from mocap import take_solve

        report = take_solve.solve_take(Path(args.take), Path(args.out))
        print(json.dumps({"frames": report["frames"], "out": args.out, "skeleton_scales": report["skeleton"]["scales"]}),
              flush=True)
        return 0
    import tempfile

    import numpy as np

    from mocap import offline, recording
    from mocap.export.bvh import write_bvh
    from mocap.export.joints_csv import write_positions_csv

    with tempfile.TemporaryDirectory() as folder:
        session = Path(args.session) if args.session else recording.read_session(args.recording, folder)
        if session is None:
            raise InputError(f"{args.recording}: no session is attached to this recording; give --session")
        poses, dropped, skeleton = offline.solve_recording(Path(args.recording), session)
    if not poses:
        raise InputError(f"{args.recording}: no frame could be solved (dropped inputs: {dropped})")
    thetas = np.array([list(p.theta) for p in poses])
    write_bvh(args.out, skeleton, thetas, offline.frame_rate(poses))  # the latest calibration's skeleton
    if args.csv:  # the bones as solved, each frame with the calibration in use then
        times = np.array([p.capture_time_ns - poses[0].capture_time_ns for p in poses]) * 1e-9
        write_positions_csv(args.csv, skeleton.bone_names, offline.joint_positions(poses), times)
    print(json.dumps({"frames": len(poses), "out": args.out, "dropped": dropped}), flush=True)
    return 0


def _simulate(args: argparse.Namespace) -> int:
    from pathlib import Path

    from mocap.sim import take_out

    print(json.dumps(take_out.run(Path(args.take_out), args.seconds, args.preset, args.seed,
                                  args.calibration_pose, args.still_start)), flush=True)
    return 0


def _detect(args: argparse.Namespace) -> int:
    from pathlib import Path

    from mocap_edge.detect.video import detect_video

    print(json.dumps(detect_video(Path(args.video), Path(args.out), max_people=args.max_people, model=args.model)),
          flush=True)
    return 0


def _eval_edge(args: argparse.Namespace) -> int:
    from mocap import real_trial
    from mocap.demo_data import fetch_trial

    print(json.dumps(real_trial.evaluate(fetch_trial()), indent=1), flush=True)
    return 0


def _train_prior(args: argparse.Namespace) -> int:
    from pathlib import Path

    from mocap import prior

    exclude = set() if args.include_test else prior.held_out_clips(Path(args.split))
    result, info = prior.train(Path(args.bvh), rate=args.rate, exclude=exclude, variance=args.variance,
                               clusters=args.clusters or None, seed=args.seed)
    prior.save(result, Path(args.out), info)
    logging.info("wrote %s: %d clips, %d frames, rank %d", args.out, len(info["clips"]), info["frames"], info["rank"])
    return 0


def _eval(args: argparse.Namespace) -> int:
    import dataclasses
    from pathlib import Path

    from mocap import eval as evaluation
    from mocap.sim import detector, take

    if args.table == "heading":
        from mocap import tables_heading

        print(tables_heading.markdown(tables_heading.rows(args.seconds), args.seconds), end="", flush=True)
        return 0
    if args.table:
        from mocap import tables

        summary = tables.write(args.seed, Path(args.docs), f"mocap eval --table paper --seed {args.seed}")
        print(json.dumps({p: round(s["pos_error_cm"], 2) for p, s in summary["configurations"].items()}), flush=True)
        return 0
    if not args.motion or not args.json:
        raise InputError("--motion and --json are needed unless --table is given")
    motion = Path(args.motion)
    clips = sorted(motion.rglob("*.bvh")) if motion.is_dir() else [motion]
    config = take.Config(preset=args.preset, cameras=args.cameras,
                         detector=dataclasses.replace(detector.DetectorErrors(), site_offsets=args.site_offsets == "on"))
    cal_options = {} if args.site_std is None else {"site_std": args.site_std / 1000.0}
    results = [evaluation.evaluate(clip, config, args.omit, args.seed, args.set, args.baseline, args.calibration, cal_options)
               for clip in clips]
    summary = evaluation.summarise(results)
    Path(args.json).write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps({k: v for k, v in summary.items() if not isinstance(v, (list, dict))}), flush=True)
    return 0


def _imu_stats(args: argparse.Namespace) -> int:
    from pathlib import Path

    from mocap.sim import imu_stats

    folder = Path(args.imu) if args.imu else paths.shared_file("data/imu")
    print(json.dumps(imu_stats.stats(folder), indent=1), flush=True)
    return 0


def _imu_filter(args: argparse.Namespace) -> int:
    from mocap.imu_node import filter as node_filter

    print(json.dumps(node_filter.filter_csv(args.input, args.out, use_mag=not args.no_mag)), flush=True)
    return 0


def _eval_imu_filter(args: argparse.Namespace) -> int:
    from mocap.imu_node import broad

    rows = broad.evaluate(broad.load(args.trials), args.methods)
    if args.markdown:
        print(broad.markdown(rows), end="", flush=True)
        return 0
    sets = {"held-out": broad.HELD_OUT, "tuning": broad.TUNING, "all": tuple(rows)}
    print(json.dumps({"trials": rows, "summary": {name: broad.summarise(rows, numbers) for name, numbers in sets.items()}},
                     indent=1), flush=True)
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="mocap", description="Real-time motion capture from video and IMUs.")
    p.add_argument("-v", "--verbose", action="store_true", help="log debug messages")
    sub = p.add_subparsers(dest="command", required=True)

    b = sub.add_parser("bench", help="run benchmarks; print one JSON object per line")
    b.add_argument("--only", nargs="+", default=["solver", "live", "edge", "firmware"],
                   choices=["solver", "live", "edge", "firmware"],
                   help="benchmarks to run (default all)")
    b.add_argument("--live-seconds", type=float, default=60.0, help="length of the live benchmark's take")
    b.add_argument("--rate", type=float, default=60.0, help="capture rate, Hz (default 60)")
    b.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    b.add_argument("--repeats", type=int, default=3, help="runs of the workload; the lowest median is kept")
    b.add_argument("--set", action="append", default=[], metavar="OPTION=VALUE",
                   help="a solver option, e.g. function_tolerance=3e-2 or acceleration.weight=0 (repeatable)")
    b.set_defaults(func=_bench)

    s = sub.add_parser("skeleton", help="write a solver skeleton file from a BVH hierarchy")
    s.add_argument("--from-bvh", required=True, help="BVH file whose hierarchy gives the bone offsets")
    s.add_argument("--scale", default="auto", help="file units to metres, or 'auto' (default)")
    s.add_argument("--out", required=True, help="skeleton JSON to write")
    s.set_defaults(func=_skeleton)

    t = sub.add_parser("train-prior", help="fit the PCA pose prior to a folder of BVH clips")
    t.add_argument("--bvh", required=True, help="folder of BVH files (searched recursively)")
    t.add_argument("--out", required=True, help="prior JSON to write")
    t.add_argument("--split", default=str(paths.HOST_DATA / "motion_split.json"),
                   help="split file whose 'test' and 'validation' clips are left out (default: the shipped one)")
    t.add_argument("--include-test", action="store_true", help="train on the test and validation clips too")
    t.add_argument("--rate", type=float, default=60.0, help="resample clips to this rate, Hz (default 60)")
    t.add_argument("--clusters", type=int, default=500, help="k-means clusters, 0 for none (default 500)")
    t.add_argument("--variance", type=float, default=0.95, help="fraction of variance kept (default 0.95)")
    t.add_argument("--seed", type=int, default=0, help="k-means seed (default 0)")
    t.set_defaults(func=_train_prior)

    e = sub.add_parser("eval", help="simulate takes of real motion, solve them and score the solver")
    e.add_argument("--motion", help="BVH file or folder of BVH files (searched recursively)")
    e.add_argument("--preset", default="hq13", choices=["hq13", "hs13", "hq6", "hs6"],
                   help="HQ: detections every frame, 8 cameras; HS: 2 of every 8 frames, 4 cameras (default hq13)")
    e.add_argument("--cameras", type=int, default=None, help="number of cameras (default: the preset's)")
    e.add_argument("--omit", nargs="*", default=[], choices=["R", "P", "A", "PP", "PD"], help="cost terms to switch off")
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
    e.add_argument("--json", help="JSON file to write the results to")
    e.add_argument("--table", choices=["paper", "heading"],
                   help="paper: regenerate the paper's tables and plots on the test clips; heading: print the "
                        "heading tracking's table (a long take of the demo motion, --seconds)")
    e.add_argument("--seconds", type=float, default=60.0, help="length of the --table heading take (default 60)")
    e.add_argument("--docs", default=str(paths.REPO / "docs"), help="where --table writes results.md (default docs/)")
    e.set_defaults(func=_eval)

    i = sub.add_parser("imu-stats", help="noise and bias figures of the real IMU recordings (for the simulator)")
    i.add_argument("--imu", default=None, help="folder of the recordings (default ../shared/data/imu)")
    i.set_defaults(func=_imu_stats)

    d = sub.add_parser("demo", help="the live system on a simulated studio: 8 cameras + 13 IMUs over loopback, "
                       "mocapd solving in real time; writes OUT/demo.bvh, demo_joints.csv, report.md")
    d.add_argument("--out", default="out", help="output folder (default out)")
    d.add_argument("--seconds", type=float, default=20.0, help="length of the take (default 20)")
    d.add_argument("--vmc", default=None, metavar="HOST:PORT", help="also stream the poses as VMC (OSC/UDP)")
    d.add_argument("--record", default=None, metavar="FILE", help="record every stream to this MCAP file")
    d.add_argument("--seed", type=int, default=0)
    d.add_argument("--calibration", default="estimated", choices=["estimated", "oracle", "live"],
                   help="estimated: calibrated from the streams' first 5 s with motion before the take (default); "
                        "live: mocapd starts from video alone and the live calibrator (mocap calibrate --follow) "
                        "calibrates, then refines, during the take; oracle: the truth")
    d.add_argument("--still-start", type=float, default=0.0, metavar="S",
                   help="the performer stands still for S seconds before moving")
    d.set_defaults(func=_demo)

    ca = sub.add_parser("calibrate", help="a live session whose skeleton and IMU mounting, heading and position are "
                        "estimated from the first seconds with motion of a recording or of the live streams "
                        "(docs/calibration.md)")
    ca.add_argument("--recording", help="MCAP file of `mocap record` / `mocap demo --record`")
    ca.add_argument("--connect", nargs="+", metavar="EP", help="instead: record live from these publishers (edge "
                    "boxes, IMU hubs; needs --session) until the IMUs moved enough, kept as OUT/calibration.mcap")
    ca.add_argument("--session", default=None, help="session giving rig, layout, IMU names and bones, endpoints "
                    "(default: the one attached to the recording)")
    ca.add_argument("--out", required=True, help="folder for the calibrated session (session.json and its files)")
    ca.add_argument("--seconds", type=float, default=5.0, help="length of the calibration window (default 5)")
    ca.add_argument("--max-seconds", type=float, default=30.0,
                    help="--connect: stop recording after this long even if the IMUs barely moved (default 30); "
                         "--follow: calibrate after this long from seconds that move less")
    ca.add_argument("--follow", action="store_true",
                    help="with --connect: keep running beside mocapd, publish a Calibration on --publish as soon as "
                         "the IMUs moved enough and a refined one when they move much more (mocap.calibrator); "
                         "the latest is also written to --out as a session")
    ca.add_argument("--publish", metavar="EP", help="--follow: where to publish (one of mocapd's inputs)")
    ca.add_argument("--duration", type=float, default=None, help="--follow: stop after this many seconds")
    ca.set_defaults(func=_calibrate)

    sm = sub.add_parser("simulate", help="simulate a take of the demo motion (cameras + IMUs) and write it as a "
                        "take folder (docs/take_format.md), with its truth (truth.json) beside it")
    sm.add_argument("--take-out", required=True, metavar="DIR", help="take folder to write")
    sm.add_argument("--seconds", type=float, default=10.0, help="length of the take (default 10)")
    sm.add_argument("--preset", default="hq13", choices=["hq13", "hs13", "hq6", "hs6"],
                    help="cameras and IMU set, as `mocap eval` (default hq13)")
    sm.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    sm.add_argument("--calibration-pose", choices=["T", "N"],
                    help="start with 1 s of a T-pose (arms out) or N-pose (arms down) and a 0.5 s blend "
                         "into the motion: the calibration uses it (docs/calibration.md)")
    sm.add_argument("--still-start", type=float, default=0.0, metavar="S",
                    help="the performer stands still for S seconds first (a pose of the motion), then moves: "
                         "the calibration waits for motion (docs/calibration.md)")
    sm.set_defaults(func=_simulate)

    de = sub.add_parser("detect", help="the edge keypoint detector (BlazePose, region tracking) on a video: "
                        "one OpenPose-style JSON per frame")
    de.add_argument("video", help="video file")
    de.add_argument("--out", required=True, help="folder of the JSON files")
    de.add_argument("--max-people", type=int, default=2, help="people tracked at once (default 2)")
    de.add_argument("--model", default="blazepose", help="blazepose (default) or a model configuration JSON "
                    "(edge/python/mocap_edge/detect/topdown.py)")
    de.set_defaults(func=_detect)

    ee = sub.add_parser("eval-edge", help="the edge detector on the real Balancing trial (PCK against OpenPose, "
                        "speed) and the video-only solve of its keypoints against Pose2Sim's TRC")
    ee.set_defaults(func=_eval_edge)

    so = sub.add_parser("solve", help="solve a recording offline through the host's pipeline (--out a BVH), or a take "
                        "folder (--out a folder: joints.csv, take.bvh, calibration report)")
    so.add_argument("--recording", default=None, help="MCAP file of `mocap record` / `mocap demo --record`")
    so.add_argument("--take", default=None, help="take folder (docs/take_format.md)")
    so.add_argument("--session", default=None, help="session file (default: the one attached to the recording)")
    so.add_argument("--out", required=True, help="BVH to write (--recording) or output folder (--take)")
    so.add_argument("--csv", default=None, help="also write joint positions as CSV")
    so.set_defaults(func=_solve)

    rec = sub.add_parser("record", help="record the streams of ZeroMQ publishers to an MCAP file (Foxglove)")
    rec.add_argument("--connect", nargs="+", required=True, metavar="EP", help="publisher endpoints, tcp://host:port")
    rec.add_argument("--out", required=True, help="MCAP file to write")
    rec.add_argument("--seconds", type=float, default=None, help="stop after this long (default: at Ctrl-C)")
    rec.add_argument("--session", default=None, help="attach this session file and the files it names "
                     "(then `mocap solve --recording` needs nothing else)")
    rec.set_defaults(func=_record)

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
    rep.set_defaults(func=_replay)

    imf = sub.add_parser("imu-filter", help="run the IMU node's orientation filter (the firmware's C) on a recording: "
                         "IN.csv t,gx,gy,gz (rad/s),ax,ay,az (m/s^2),mx,my,mz (uT), sensor frame -> OUT.csv "
                         "t,qw,qx,qy,qz (sensor -> ENU)")
    imf.add_argument("--in", dest="input", required=True, metavar="IN.csv", help="recording, header row first; the "
                     "sample period is the median dt (each dt within 5 %% of it); a NaN value skips that vector")
    imf.add_argument("--out", required=True, metavar="OUT.csv", help="orientations to write, one row per input row")
    imf.add_argument("--no-mag", action="store_true", help="6D: ignore the magnetometer (heading from the gyroscope)")
    imf.set_defaults(func=_imu_filter)

    eif = sub.add_parser("eval-imu-filter", help="the node's filter (9D, 6D), VQF and Fusion on the BROAD benchmark "
                         "(../shared/data/imu/broad): RMSE in degrees (docs/firmware.md)")
    eif.add_argument("--trials", nargs="+", default=None, metavar="NN",
                     help="trial numbers, e.g. 02 03 (default all 18; tuning: 01 04 06 08 10 24 26 28)")
    eif.add_argument("--methods", nargs="+", default=None, metavar="METHOD",
                     help="a subset of: 'ours 9D' 'ours 6D' 'VQF 9D' 'VQF 6D' 'Fusion 9D' (default all)")
    eif.add_argument("--markdown", action="store_true", help="print the tables (held-out, all, per trial) as Markdown")
    eif.set_defaults(func=_eval_imu_filter)

    r = sub.add_parser("rig", help="write a rig file from a Pose2Sim/anipose Calib.toml")
    r.add_argument("--from-calib-toml", required=True, help="Calib.toml to read")
    r.add_argument("--out", required=True, help="rig JSON to write")
    r.set_defaults(func=_rig)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.DEBUG if args.verbose else logging.INFO, format="%(levelname)s %(message)s")
    try:
        return args.func(args)
    except (MocapError, EdgeError, OSError, ValueError) as e:
        print(f"mocap {args.command}: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
