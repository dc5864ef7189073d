"""python -m mocap_edge camera --source URI --camera ID --bind ENDPOINT [--hs PERIOD BURST] [--realtime]
   python -m mocap_edge camera|imu-hub --streams FILE --bind ENDPOINT --start-ns T   (simulated studio)"""

from __future__ import annotations

import argparse
import sys

import time

from mocap_edge import camera_node, imu_hub
from mocap_edge.streams import Streams


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="mocap_edge", description="an edge box playing a stream file in real time")
    p.add_argument("role", choices=["camera", "imu-hub"])
    p.add_argument("--source", help="role camera: capture and detect from a frame source, e.g. video:cam01.mp4, "
                   "v4l2:/dev/video0, libcamera:0, images:DIR (with --fps)")
    p.add_argument("--fps", type=float, default=None, help="frame rate of an images: source")
    p.add_argument("--hs", nargs=2, type=int, default=(1, 1), metavar=("PERIOD", "BURST"),
                   help="detect on BURST consecutive frames of every PERIOD (high-speed mode)")
    p.add_argument("--realtime", action="store_true", help="play a file source at its capture times")
    p.add_argument("--model", default="blazepose", help="keypoint model: blazepose or a configuration JSON")
    p.add_argument("--trigger", metavar="CHIP:LINE", help="pair frames with the rising edges of this GPIO line "
                   "(e.g. /dev/gpiochip0:17; docs/sync.md)")
    p.add_argument("--exposure-mid-us", type=float, default=0.0,
                   help="with --trigger: trigger edge to mid-exposure (sensor delay + exposure / 2), microseconds")
    p.add_argument("--streams", help="stream file of the simulated studio (.npz, mocap_edge.streams)")
    p.add_argument("--bind", required=True, help="ZeroMQ endpoint to publish on, e.g. tcp://*:5601")
    p.add_argument("--start-ns", type=int, default=None, help="take start on the shared timebase (ns; default now)")
    p.add_argument("--camera", help="camera id (role camera)")
    p.add_argument("--stop", nargs=2, type=float, metavar=("FROM_S", "TO_S"), help="unplug during this span")
    p.add_argument("--stop-sensor", help="sensor silenced during --stop (role imu-hub)")
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args(argv)
    if a.start_ns is None:
        a.start_ns = time.time_ns()
    if a.role == "camera" and a.source:
        return _camera_box(a)
    if not a.streams:
        p.error("--streams (simulated studio) or, for a camera, --source is needed")
    streams = Streams.load(a.streams)
    if a.role == "camera":
        n = camera_node.run(streams, a.camera, a.bind, a.start_ns, seed=a.seed, stop_at=tuple(a.stop) if a.stop else None)
        print(f"{a.camera}: {n} frames sent", file=sys.stderr)
    else:
        stop = (a.stop_sensor, *a.stop) if a.stop_sensor and a.stop else None
        n = imu_hub.run(streams, a.bind, a.start_ns, stop_sensor=stop)
        print(f"imu hub: {n} batches sent", file=sys.stderr)
    return 0


def _camera_box(a) -> int:
    from mocap_edge import camera_box
    from mocap_edge.detect.topdown import load_model
    from mocap_edge.trigger import GpiodTrigger, TriggerPairing
    from mocap_edge.errors import EdgeError
    from mocap_edge.sources.base import open_source

    scheme = a.source.partition(":")[0]
    options = ({"start_ns": a.start_ns} if scheme in ("video", "images", "fake") else {}) | (
        {"fps": a.fps} if a.fps else {})
    try:
        with open_source(a.source, **options) as source:
            pairing = None
            if a.trigger:
                chip, _, line = a.trigger.rpartition(":")
                pairing = TriggerPairing(GpiodTrigger(chip, int(line)), source.nominal_fps)
            counts = camera_box.run(source, a.camera or "cam0", a.bind, tuple(a.hs), pairing=pairing,
                                    realtime=a.realtime, model=load_model(a.model),
                                    exposure_mid_ns=round(a.exposure_mid_us * 1000))
    except (EdgeError, ValueError) as e:  # ValueError: a --trigger line that is not a number
        print(f"mocap_edge: {e}", file=sys.stderr)
        return 1
    print(f"{a.camera}: {counts.frames} frames sent, {counts.detected} detected, {counts.people} people",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
