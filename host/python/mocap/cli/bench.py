"""`mocap bench`: benchmarks, one JSON object per line (solver, live, stage, multi, monitor, edge, firmware, hub, peer,
recording, drill, batch, scale; soak only when asked: it runs for minutes)."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from mocap.batch import bench as batch_bench
from mocap.demo import drill, monitor_bench, people_stage, record_drill, soak, stage
from mocap.demo import score as live
from mocap.errors import DataMissingError, InputError, MocapError
from mocap.eval import bench, edge_detector, peer, people, scale_plot
from mocap.imu_node import bench as firmware_bench
from mocap.io.demo_data import fetch_trial
from mocap_edge.hub import bench as hub_bench

KINDS = ["solver", "live", "stage", "multi", "monitor", "edge", "firmware", "hub", "peer", "recording", "drill", "batch",
         "scale"]
ON_REQUEST = ["soak"]  # not in the default run: it lasts --minutes


def register(sub: argparse._SubParsersAction) -> None:
    b = sub.add_parser("bench", help="run benchmarks; print one JSON object per line")
    b.add_argument("--only", nargs="+", default=KINDS, choices=KINDS + ON_REQUEST,
                   help="benchmarks to run (default all but soak)")
    b.add_argument("--minutes", type=float, default=10.0, help="length of the soak's take (default 10)")
    b.add_argument("--pin-host", action="store_true", help="soak: mocapd alone on the last core, the studio's other "
                   "processes on the others (as systemd's CPUAffinity= on a deployed host)")
    b.add_argument("--live-seconds", type=float, default=60.0, help="length of the live benchmark's take")
    b.add_argument("--live-cameras", type=int, nargs="+", default=[8], metavar="N",
                   help="the live benchmark's camera counts, one line each (default 8)")
    b.add_argument("--stage-cameras", type=int, default=32, metavar="N",
                   help="cameras of the stage benchmark: the live host fed by one replay (default 32)")
    b.add_argument("--live-normal-priority", action="store_true",
                   help="run the live and soak benchmarks' mocapd without --realtime (to see what real-time "
                        "scheduling buys)")
    b.add_argument("--monitor-seconds", type=float, default=30.0,
                   help="length of the take with the live view open (default 30)")
    b.add_argument("--screenshot", default=None, metavar="PNG", help="the live view halfway through that take")
    b.add_argument("--plot", default=None, metavar="PNG", help="scale: the cost against the cameras drawn into PNG")
    b.add_argument("--rate", type=float, default=60.0, help="capture rate, Hz (default 60)")
    b.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    b.add_argument("--repeats", type=int, default=3, help="runs of the workload; the lowest median is kept")
    b.add_argument("--set", action="append", default=[], metavar="OPTION=VALUE",
                   help="a solver option, e.g. function_tolerance=3e-2 or acceleration.weight=0 (repeatable)")
    b.set_defaults(func=run)


def _check(args: argparse.Namespace) -> None:
    """Lengths and counts a benchmark can run with: finite, positive."""
    lengths = {"--minutes": args.minutes, "--live-seconds": args.live_seconds, "--monitor-seconds": args.monitor_seconds}
    for name, value in lengths.items():
        if not math.isfinite(value) or value <= 0:
            raise InputError(f"{name} must be a positive number of {name.split('-')[-1]}, not {value}")
    if any(n < 1 for n in args.live_cameras):
        raise InputError(f"--live-cameras: each count must be at least 1, not {args.live_cameras}")
    if args.stage_cameras < 1:
        raise InputError(f"--stage-cameras must be at least 1, not {args.stage_cameras}")


def _line(name: str, measure, missing=DataMissingError) -> None:
    """Prints measure()'s figures, or that the benchmark was skipped as its data is missing."""
    try:
        print(json.dumps(measure()), flush=True)
    except missing as e:
        print(json.dumps({"bench": name, "skipped": str(e)}), flush=True)


def _whole_machine(args: argparse.Namespace) -> None:
    """The benchmarks of processes and threads that get both cores."""
    if "live" in args.only:  # before pinning: the edge processes and mocapd get the whole machine
        for cameras in args.live_cameras:
            print(json.dumps(live.bench(args.live_seconds, not args.live_normal_priority, cameras)), flush=True)
    if "stage" in args.only:  # the live host before 32 cameras, fed by one replay process
        print(json.dumps(stage.bench(args.live_seconds, args.stage_cameras, not args.live_normal_priority)), flush=True)
    if "multi" in args.only:  # 3 people: the tracker's frame on both cores and on one, then mocapd live
        _line("multi", lambda: {**people.bench(seed=args.seed),
                                "live": people_stage.bench(seed=args.seed, realtime=not args.live_normal_priority)})
    if "monitor" in args.only:  # the live benchmark with the live view open in headless Chromium
        _line("monitor", lambda: monitor_bench.bench(args.monitor_seconds, realtime=not args.live_normal_priority,
                                                     screenshot=Path(args.screenshot) if args.screenshot else None))
    if "recording" in args.only:  # the recorder killed mid-take: what its file keeps
        print(json.dumps(record_drill.bench()), flush=True)
    if "drill" in args.only:  # camera box, IMU hub and mocapd killed, a box's clock stepped, mid-take
        for line in drill.bench():
            print(json.dumps({"bench": "drill", **line}), flush=True)
    if "soak" in args.only:  # the live studio for --minutes: latency windows, memory, descriptors
        print(json.dumps(soak.bench(args.minutes, realtime=not args.live_normal_priority, pin_host=args.pin_host)),
              flush=True)
    if "batch" in args.only:  # the same takes serially and on a LocalCluster of two workers (both cores)
        _line("batch", batch_bench.bench)
    if "edge" in args.only:
        _line("edge", lambda: edge_detector.bench(fetch_trial()))
    if "firmware" in args.only:
        print(json.dumps(firmware_bench.firmware()), flush=True)


def _scale(args: argparse.Namespace) -> dict:
    result = bench.scale(rate=args.rate, seed=args.seed, repeats=args.repeats)
    if args.plot:
        scale_plot.plot(result, Path(args.plot))
    return result


def run(args: argparse.Namespace) -> int:
    _check(args)
    _whole_machine(args)
    bench.pin_to_one_core()
    if "hub" in args.only:  # frames decoded per second on one core
        print(json.dumps(hub_bench.hub()), flush=True)
    if "solver" in args.only:
        _line("solver", lambda: bench.solver(rate=args.rate, seed=args.seed, repeats=args.repeats, settings=args.set))
    if "scale" in args.only:  # the solve's cost against cameras (1-32), IMUs and keypoints, on this core
        _line("scale", lambda: _scale(args))
    if "peer" in args.only:  # ours against Pose2Sim's triangulation, both on this core
        _line("peer", lambda: peer.bench(repeats=args.repeats), MocapError)  # the trial missing or unreadable
    return 0
