"""python -m mocap_edge camera|imu-hub --streams FILE --bind ENDPOINT --start-ns T ..."""

from __future__ import annotations

import argparse
import sys

from mocap_edge import camera_node, imu_hub
from mocap_edge.streams import Streams


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="mocap_edge", description="an edge box playing a stream file in real time")
    p.add_argument("role", choices=["camera", "imu-hub"])
    p.add_argument("--streams", required=True, help="stream file (.npz, mocap_edge.streams)")
    p.add_argument("--bind", required=True, help="ZeroMQ endpoint to publish on, e.g. tcp://*:5601")
    p.add_argument("--start-ns", type=int, required=True, help="take start on the shared timebase (ns)")
    p.add_argument("--camera", help="camera id (role camera)")
    p.add_argument("--stop", nargs=2, type=float, metavar=("FROM_S", "TO_S"), help="unplug during this span")
    p.add_argument("--stop-sensor", help="sensor silenced during --stop (role imu-hub)")
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args(argv)
    streams = Streams.load(a.streams)
    if a.role == "camera":
        n = camera_node.run(streams, a.camera, a.bind, a.start_ns, seed=a.seed, stop_at=tuple(a.stop) if a.stop else None)
        print(f"{a.camera}: {n} frames sent", file=sys.stderr)
    else:
        stop = (a.stop_sensor, *a.stop) if a.stop_sensor and a.stop else None
        n = imu_hub.run(streams, a.bind, a.start_ns, stop_sensor=stop)
        print(f"imu hub: {n} batches sent", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
