"""The simulated studio (mocap.demo.studio) played live: mocapd, one camera box per camera
(`python -m mocap_edge camera --source sim:STREAMS`: the box's own loop on the simulated
backend), the IMU hub and, for a live calibration, the live calibrator — all on loopback —
and a consumer collecting PoseFrame and Health until the take ends."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
import signal
import time
from collections.abc import Callable
from pathlib import Path

import zmq

from mocap import paths
from mocap.demo.studio import Studio
from mocap.errors import InputError
from mocap.io.session import Session
from mocap.net import transport, wire

MOCAPD = paths.REPO / "build" / "host" / "mocapd"
LEAD_S = 4.0  # between launching the processes and the take's first frame
# mocapd solves under SCHED_FIFO at this priority (README, "Pointing it at real edge boxes"): here
# a dozen edge processes share its cores; without the permission it warns and goes on.
REALTIME_PRIORITY = 10


def camera_box_command(studio: Studio, c: int, start_ns: int, unplugged: tuple | None = None) -> list[str]:
    """The camera box of camera c on the simulated backend (its detection latency seeded by
    c); unplugged (camera id, from_s, to_s): that box is unplugged during the span."""
    camera = studio.camera_ids[c]
    cmd = [sys.executable, "-m", "mocap_edge", "camera", "--source", f"sim:{studio.streams}", "--camera", camera,
           "--bind", studio.endpoints[camera], "--start-ns", str(start_ns), "--seed", str(c)]
    if studio.detect_every[0] > 1:
        cmd += ["--hs", *map(str, studio.detect_every)]
    if unplugged and unplugged[0] == camera:
        cmd += ["--stop", *map(str, unplugged[1:])]
    return cmd + _box_keys(studio, camera)


def _box_keys(studio: Studio, device: str) -> list[str]:
    """A box's key options in a studio with keys: its secret key, and the host admitted."""
    if studio.keys is None:
        return []
    return ["--curve-secret", str(studio.keys / f"{device}.key"), "--curve-allow", str(studio.keys / "host.pub")]


def start_sim_nodes(studio: Studio, start_ns: int, unplugged: tuple | None = None) -> tuple[subprocess.Popen, int]:
    """The studio's IMUs as sensor nodes (`mocap_edge sim-nodes`, served as a CAN bus over
    TCP), and the port they listen on. unplugged (sensor id, from_s, to_s): that sensor's node
    is unplugged during the span."""
    nodes_cmd = [sys.executable, "-m", "mocap_edge", "sim-nodes", "--streams", str(studio.streams),
                 "--config", str(studio.hub_config), "--port", "0", "--start-ns", str(start_ns)]
    if unplugged:
        nodes_cmd += ["--stop-sensor", unplugged[0], "--stop", *map(str, unplugged[1:])]
    nodes = subprocess.Popen(nodes_cmd, stdout=subprocess.PIPE, text=True)
    listening = nodes.stdout.readline().split()  # "listening PORT"
    if len(listening) != 2:
        nodes.kill()
        raise InputError(f"the simulated sensor nodes did not start (status {nodes.wait()}; their log is above)")
    return nodes, int(listening[1])


def imu_hub_command(studio: Studio, nodes_port: int) -> list[str]:
    """The IMU hub (`mocap_edge imu-hub --can socketcand:...`) reading the nodes on nodes_port."""
    return [sys.executable, "-m", "mocap_edge", "imu-hub", "--can", f"socketcand:127.0.0.1:{nodes_port}:can0",
            "--config", str(studio.hub_config), "--bind", studio.endpoints["hub0"], *_box_keys(studio, "hub0")]


def _start_imu_hub(studio: Studio, start_ns: int, unplugged: tuple | None) -> list[subprocess.Popen]:
    """The sensor nodes, then the hub reading them: the hub connects once the nodes listen."""
    nodes, port = start_sim_nodes(studio, start_ns, unplugged)
    hub = subprocess.Popen(imu_hub_command(studio, port))
    return [hub, nodes]  # stopped in this order: the hub never sees its bus go away


def _calibrator_command(studio: Studio, duration: float, lead_s: float = LEAD_S) -> list[str]:
    """The live calibrator beside mocapd (`mocap calibrate --follow`)."""
    edge_endpoints = [studio.endpoints[c] for c in [*studio.camera_ids, "hub0"]]
    return [sys.executable, "-m", "mocap.cli", "calibrate", "--connect", *edge_endpoints,
            "--session", str(studio.session), "--out", str(studio.calibrated), "--follow",
            "--publish", studio.calibrator, "--duration", f"{lead_s + duration + 1.0:.3f}"]


def recorder_command(studio: Studio, path: Path, duration: float, lead_s: float = LEAD_S) -> list[str]:
    """`mocap record` of every stream (the edge boxes', the calibrator's, mocapd's poses and
    Health), with the session attached. A process of its
    own, as in a studio: a recorder thread in this process shared the interpreter with the
    consumer, and its arrival stamps came up to tens of ms late — later than the synchroniser
    waits — so the recording solved again dropped camera frames mocapd had used."""
    inputs = [*studio.endpoints.values(), *([studio.calibrator] if studio.calibrator else [])]
    return [sys.executable, "-m", "mocap.cli", "record", "--connect", *inputs, "--out", str(path),
            "--session", str(studio.session), "--seconds", f"{lead_s + duration + 2.0:.3f}"]


@dataclasses.dataclass
class Run:
    poses: list  # PoseFrame messages in arrival order
    healths: list
    host_summary: dict
    start_ns: int


def collect(host: subprocess.Popen, sub: zmq.Socket, progress: Callable | None,
             on_pose: Callable | None) -> tuple[list, list]:
    """PoseFrame and Health messages from mocapd until it exits; each Health to progress,
    each PoseFrame to on_pose."""
    poses, healths = [], []
    while host.poll() is None:
        if not sub.poll(200):
            continue
        while True:
            try:
                frames = sub.recv_multipart(zmq.NOBLOCK)
            except zmq.Again:
                break
            try:
                msg = wire.decode(frames)
            except wire.WireError:
                continue
            if isinstance(msg, wire.PoseFrame):
                poses.append(msg)
                if on_pose:
                    on_pose(msg)
            elif isinstance(msg, wire.Health):
                healths.append(msg)
                if progress:
                    progress(msg)
    return poses, healths


def mocapd_command(session: Path, duration_s: float, realtime: bool) -> list[str]:
    """mocapd on `session` for duration_s, quiet; SCHED_FIFO at REALTIME_PRIORITY if realtime."""
    priority = ["--realtime", str(REALTIME_PRIORITY)] if realtime else []
    return [str(MOCAPD), str(session), "--duration", f"{duration_s:.3f}", "--quiet", *priority]


def published(host: subprocess.Popen, sub: zmq.Socket, others: list, progress: Callable | None = None,
              on_pose: Callable | None = None) -> tuple[list, list, dict]:
    """The poses and Health mocapd (`host`, started with its stdout piped) published on `sub`
    until it exits, and its summary line; InputError when it failed or gave no summary. The
    processes feeding it (`others`) and mocapd itself are stopped, and `sub` closed, after."""
    try:
        poses, healths = collect(host, sub, progress, on_pose)
        lines = host.stdout.read().strip().splitlines()
        if host.wait() != 0 or not lines:
            raise InputError(f"mocapd stopped with status {host.returncode} (its log is above)")
        return poses, healths, json.loads(lines[-1])
    finally:
        for p in [*others, host]:
            if p.poll() is None:
                p.terminate()
            p.wait(timeout=10)
        sub.close()


def play(studio: Studio, progress: Callable | None = None, faults: dict | None = None, on_pose: Callable | None = None,
         record: Path | None = None, realtime: bool = True, lead_s: float = LEAD_S) -> Run:
    """Plays the studio live: mocapd + one process per camera + the IMU hub, all on
    loopback, until the take ends. progress(health) is called once a second; on_pose(pose)
    for every PoseFrame. faults: {"camera": (id, from_s, to_s), "imu": (id, from_s, to_s)}.
    realtime: mocapd asks for SCHED_FIFO at REALTIME_PRIORITY; lead_s: between launching the
    processes and the take's first frame."""
    if not MOCAPD.exists():
        raise InputError(f"{MOCAPD} is missing: run `make build`")
    faults = faults or {}
    duration = float(studio.frame_times[-1])
    start_ns = time.time_ns() + int(lead_s * 1e9)
    host = subprocess.Popen(mocapd_command(studio.session, lead_s + duration + 1.5, realtime), stdout=subprocess.PIPE,
                            text=True)
    commands = [camera_box_command(studio, c, start_ns, faults.get("camera")) for c in range(len(studio.camera_ids))]
    if studio.calibrator:
        commands.append(_calibrator_command(studio, duration, lead_s))
    edge = [subprocess.Popen(cmd) for cmd in commands]
    edge += _start_imu_hub(studio, start_ns, faults.get("imu"))
    recording = subprocess.Popen(recorder_command(studio, record, duration, lead_s)) if record else None
    keys = Session.load(studio.session).client_keys()  # None: a studio without keys (the default)
    sub = transport.subscriber(zmq.Context.instance(), [studio.endpoints["host"]], keys=keys)
    try:
        poses, healths, summary = published(host, sub, edge, progress, on_pose)
    finally:
        if recording is not None:  # it closes its file on SIGINT, as at Ctrl-C
            recording.send_signal(signal.SIGINT)
            recording.wait(timeout=10)
    return Run(poses, healths, summary, start_ns)
