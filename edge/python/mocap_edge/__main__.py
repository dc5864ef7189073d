"""python -m mocap_edge camera --source URI --camera ID --bind ENDPOINT [--model M] [--hs PERIOD BURST]
       [--realtime] [--trigger CHIP:LINE --exposure-mid-us US]
   python -m mocap_edge camera --source sim:STREAMS --camera ID --bind ENDPOINT --start-ns T [--seed S]
       [--stop FROM_S TO_S] [--from-open] [--clock-step AT_S OFFSET_S]...  (a box of the simulated studio)
   python -m mocap_edge imu-hub [--can URI] [--i2c URI] --config hub.toml --bind ENDPOINT [--duration S]
   camera and imu-hub take [--curve-secret FILE [--curve-allow KEY_OR_FILE...]]: the stream authenticated
   and encrypted with the box's CURVE key (README, "Securing the streams")
                                                   (the IMU hub: sensor nodes on CAN, IMUs on its I2C)
   python -m mocap_edge sim-nodes --streams STREAMS --config hub.toml --port PORT --start-ns T
       [--stop FROM_S TO_S --stop-sensor S]        (the simulated studio's IMUs as sensor nodes, served
                                                    for a hub's --can socketcand:127.0.0.1:PORT:can0)"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import time

import zmq

from mocap.net import keys, transport
from mocap.net.keys import ServerKeys

from mocap_edge import camera_box, pacing
from mocap_edge.detect.base import Detector, open_detector
from mocap_edge.errors import EdgeError, SourceError, TriggerError
from mocap_edge.hub import command as hub_command
from mocap_edge.sources.base import open_source
from mocap_edge.supervisor import Supervisor
from mocap_edge.trigger import GpiodTrigger, TriggerPairing

Span = tuple[float, float]  # from_s, to_s of the take


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="mocap_edge", description="an edge box: a camera box (a real camera, a "
                                "video, or a camera of the simulated studio) or an IMU hub (sensor nodes on CAN, "
                                "or the simulated studio's IMUs as sensor nodes)")
    p.add_argument("role", choices=["camera", "imu-hub", "sim-nodes"])
    p.add_argument("--source", help="role camera: the frame source, e.g. libcamera:0, v4l2:/dev/video0, "
                   "video:cam01.mp4, images:DIR (with --fps), fake:, sim:STREAMS (a camera of the simulated studio)")
    p.add_argument("--fps", type=float, default=None, help="frame rate of an images: source, or what a camera "
                   "(libcamera:, v4l2:) is asked for")
    p.add_argument("--size", metavar="WxH", help="a camera's (libcamera:, v4l2:) frame size, e.g. 1280x720")
    p.add_argument("--hs", nargs=2, type=int, default=(1, 1), metavar=("PERIOD", "BURST"),
                   help="detect on BURST consecutive frames of every PERIOD (high-speed mode)")
    p.add_argument("--realtime", action="store_true", help="play a file source at its capture times")
    p.add_argument("--max-people", type=int, default=camera_box.MAX_PEOPLE,
                   help=f"people tracked per frame (default {camera_box.MAX_PEOPLE})")
    p.add_argument("--redetect-every", type=int, default=camera_box.REDETECT_EVERY, metavar="FRAMES",
                   help="the person detector looks for newcomers every FRAMES frames while people are tracked "
                        f"(default {camera_box.REDETECT_EVERY}; 0: only once everyone is lost)")
    p.add_argument("--model", help="keypoint model: blazepose (the default), a model configuration JSON, fake:, "
                   "or sim:STREAMS (the default with a sim: source)")
    p.add_argument("--trigger", metavar="CHIP:LINE", help="pair frames with the rising edges of this GPIO line "
                   "(e.g. /dev/gpiochip0:17; docs/sync.md)")
    p.add_argument("--exposure-mid-us", type=float, default=0.0,
                   help="with --trigger: trigger edge to mid-exposure (sensor delay + exposure / 2), microseconds")
    p.add_argument("--can", help="role imu-hub: the sensor nodes' CAN bus: socketcan:can0, slcan:socket://HOST:PORT, "
                   "slcan:/dev/ttyACM0, socketcand:HOST:PORT:CHANNEL or virtual:NAME")
    p.add_argument("--i2c", help="role imu-hub: the hub's own I2C bus with the IMUs of hub.toml's [i2c]: "
                   "/dev/i2c-1 or i2c:1 (fake: a simulated chip at 0x68)")
    p.add_argument("--config", help="roles imu-hub and sim-nodes: hub.toml (node ids -> sensor names, rate, ranges)")
    p.add_argument("--duration", type=float, default=0.0, help="role imu-hub: stop after this many s")
    p.add_argument("--streams", help="role sim-nodes: stream file of the simulated studio (.npz, mocap_edge.streams)")
    p.add_argument("--port", type=int, help="role sim-nodes: TCP port to serve the nodes on (socketcand protocol)")
    p.add_argument("--bind", help="roles camera and imu-hub: ZeroMQ endpoint to publish on, e.g. tcp://*:5601")
    p.add_argument("--start-ns", type=int, default=None, help="take start on the shared timebase (ns; default now): "
                   "the capture time of a file's, fake or simulated source's first frame")
    p.add_argument("--camera", default="cam0", help="camera id (role camera; with sim:, the stream file's camera)")
    p.add_argument("--stop", nargs=2, type=float, metavar=("FROM_S", "TO_S"),
                   help="unplug during this span of the take: a sim: camera box (its socket closed, bound again "
                   "after), or sim-nodes' --stop-sensor")
    p.add_argument("--from-open", action="store_true",
                   help="a sim: box started during the take captures from then on, as a camera does (by default "
                   "it sends the frames it missed at once: a box slow to start still delivers the take's start)")
    p.add_argument("--clock-step", nargs=2, type=float, action="append", default=[], metavar=("AT_S", "OFFSET_S"),
                   help="a sim: camera box's clock reads OFFSET_S off the shared timebase from take time AT_S on "
                   "(a PTP loss; OFFSET_S 0: locked again); repeatable")
    p.add_argument("--stop-sensor", help="role sim-nodes: the sensor whose node is unplugged during --stop")
    p.add_argument("--seed", type=int, default=0, help="seed of the simulated detection latency (sim: model)")
    p.add_argument("--curve-secret", metavar="FILE", help="roles camera and imu-hub: the box's secret key file "
                   "(`mocap keys`): publish as a CURVE server, only to subscribers that expect its public key")
    p.add_argument("--curve-allow", nargs="+", metavar="KEY_OR_FILE", help="with --curve-secret: the subscribers "
                   "admitted (public keys, or .pub files: the host's); without it any that knows the box's key")
    return p


def _refused(a: argparse.Namespace) -> str:
    """The exit line's count of subscribers the box refused (with --curve-allow)."""
    return f"; {transport.refused(zmq.Context.instance())} subscribers refused" if a.curve_allow else ""


def _keys(a: argparse.Namespace) -> ServerKeys | None:
    """The box's CURVE identity from --curve-secret / --curve-allow (None without them)."""
    if a.curve_secret is None:
        if a.curve_allow:
            raise EdgeError("--curve-allow needs --curve-secret")
        return None
    try:
        pair = keys.read_secret(a.curve_secret)
        allowed = frozenset(keys.read_public(k) for k in a.curve_allow) if a.curve_allow else None
    except keys.KeyFileError as e:
        raise EdgeError(str(e)) from None
    return ServerKeys(pair, allowed)


def parse_arguments(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line checked as far as it can be without opening a device (exits with a
    usage error otherwise): what the box's systemd units are tested with."""
    p = parser()
    a = p.parse_args(argv)
    missing = {"camera": ["source", "bind"], "imu-hub": ["config", "bind"],
               "sim-nodes": ["streams", "config", "port"]}[a.role]
    if any(getattr(a, m) is None for m in missing):
        p.error(f"role {a.role} needs {', '.join('--' + m for m in missing)}")
    if not a.camera.strip():  # an empty setting in a box's settings file
        p.error("--camera is empty: the camera id the host's calibration knows this camera by")
    if a.max_people < 1 or a.redetect_every < 0:
        p.error(f"--max-people must be at least 1 and --redetect-every 0 or more, not {a.max_people} and "
                f"{a.redetect_every}")
    try:  # the specs read when the box starts its source and trigger
        if a.size:
            _size(a.size, a.source.partition(":")[0])
        if a.trigger:
            _trigger_spec(a.trigger)
    except EdgeError as e:
        p.error(str(e))
    return a


def main(argv: list[str] | None = None) -> int:
    a = parse_arguments(argv)
    if a.start_ns is None:
        a.start_ns = time.time_ns()
    supervisor = Supervisor()  # systemd's READY and watchdog, where systemd runs the box
    try:
        if a.role == "imu-hub":
            return hub_command.hub(a.can, a.i2c, a.config, a.bind, a.duration, _keys(a), supervisor)
        if a.role == "sim-nodes":
            unplugged = (a.stop_sensor, *a.stop) if a.stop_sensor and a.stop else None
            return hub_command.sim_nodes(a.streams, a.config, a.port, a.start_ns, a.seed, unplugged)
        return _camera(a, supervisor)
    except EdgeError as e:
        print(f"mocap_edge: {e}", file=sys.stderr)
        return 1
    finally:
        supervisor.close()


def _camera(a: argparse.Namespace, supervisor: Supervisor) -> int:
    counts = camera_box.BoxCounts()
    for span in _spans(a):
        counts += _run_box(a, span, supervisor)
    print(f"{a.camera}: {counts.frames} frames sent, {counts.detected} detected, {counts.people} people"
          + _refused(a), file=sys.stderr)
    return 0


def _spans(a: argparse.Namespace) -> list[Span | None]:
    """When the box is on: all along, or before and after the span it is unplugged (--stop)."""
    if a.clock_step and not a.source.startswith("sim:"):
        raise EdgeError("--clock-step offsets a simulated box's clock: it needs a sim: source")
    if not a.stop:
        return [None]
    if not a.source.startswith("sim:"):
        raise EdgeError("--stop unplugs a simulated box: it needs a sim: source")
    return [(-math.inf, a.stop[0]), (a.stop[1], math.inf)]


def _run_box(a: argparse.Namespace, span: Span | None, supervisor: Supervisor) -> camera_box.BoxCounts:
    """The box from its start (plugged in at the span's start) to the end of its source."""
    if span and span[0] > -math.inf:
        pacing.sleep_until(a.start_ns + round(span[0] * 1e9))
    with contextlib.ExitStack() as stack:
        source = stack.enter_context(open_source(a.source, **_source_options(a, span)))
        pairing = None
        if a.trigger:
            pairing = TriggerPairing(stack.enter_context(_trigger(a.trigger)), source.nominal_fps)
        frames = supervisor.each(source)  # a turn per frame: READY at the first, then the watchdog
        return camera_box.run(frames, a.camera, a.bind, tuple(a.hs), pairing=pairing, realtime=a.realtime,
                              model=_model(a), exposure_mid_ns=round(a.exposure_mid_us * 1000), keys=_keys(a),
                              max_people=a.max_people, redetect_every=a.redetect_every)


def _source_options(a: argparse.Namespace, span: Span | None) -> dict[str, object]:
    scheme = a.source.partition(":")[0]
    options: dict[str, object] = {"start_ns": a.start_ns} if scheme in ("video", "images", "fake", "sim") else {}
    if a.fps:
        options["fps"] = a.fps
    if a.size:
        options.update(_size(a.size, scheme))
    if scheme == "sim":
        options.update(camera=a.camera, live=a.from_open, clock_steps=tuple(map(tuple, a.clock_step)))
        if span:
            options["span"] = span
    return options


def _size(spec: str, scheme: str) -> dict[str, int]:
    width, x, height = spec.partition("x")
    if scheme not in ("libcamera", "v4l2"):
        raise SourceError(f"--size is for a camera (libcamera:, v4l2:), not a {scheme}: source")
    if not (x and width.isdigit() and height.isdigit()):
        raise SourceError(f"--size {spec}: expected WIDTHxHEIGHT, e.g. 1280x720")
    return {"width": int(width), "height": int(height)}


def _model(a: argparse.Namespace) -> Detector:
    spec = a.model or (a.source if a.source.startswith("sim:") else "blazepose")
    if spec.startswith("sim:"):
        return open_detector(spec, camera=a.camera, start_ns=a.start_ns, seed=a.seed)
    return open_detector(spec)


def _trigger_spec(spec: str) -> tuple[str, int]:
    chip, _, line = spec.rpartition(":")
    if not chip or not line.isdigit():
        raise TriggerError(f"--trigger {spec}: expected CHIP:LINE, e.g. /dev/gpiochip0:17")
    return chip, int(line)


def _trigger(spec: str) -> GpiodTrigger:
    return GpiodTrigger(*_trigger_spec(spec))


if __name__ == "__main__":
    sys.exit(main())
