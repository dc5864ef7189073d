"""A simulated studio ready to be played live (mocap.demo.play): the demo motion simulated
(mocap.sim), written as the stream file the edge boxes play (mocap_edge.streams) and as the
session mocapd solves (mocap.io.session), with the truth kept to score the poses against.

The session's calibration is estimated from the streams' first seconds with motion before
the take (as `mocap calibrate` makes a studio's session), the truth's ("oracle"), or, with
"live", estimated during the take by the live calibrator (mocap.calibration.live; the
session starts with the default skeleton and its IMUs uncalibrated).
"""

from __future__ import annotations

import dataclasses
import json
import socket
from pathlib import Path

import numpy as np

from mocap import _core, paths
from mocap.calibration import from_messages, window
from mocap.errors import InputError
from mocap.io.session import CurveSettings, Session, SyncSettings
from mocap.model.solver import imu_set_json
from mocap.net import keys, wire
from mocap.sim import demo_motion
from mocap.sim import take as sim_take
from mocap_edge import offline
from mocap_edge.hub.sim.studio import studio_config
from mocap_edge.streams import Streams

IMU_RATE = 100.0  # Hz
# mocapd's wait for a frame's inputs: the IMUs' next sample (up to a period, 10 ms) crosses the
# simulated CAN bus, the hub and ZeroMQ, on two cores shared by a dozen processes; with 25 ms,
# 6 frames in 1,200 were handed over before the last IMU's sample arrived (20 s demo).
MAX_WAIT_MS = 35.0


@dataclasses.dataclass
class Studio:
    """A simulated take ready to be played: its session folder and truth."""
    session: Path
    streams: Path
    skeleton: _core.Skeleton  # the truth's
    truth: np.ndarray  # (F, 66) at the frame times
    frame_times: np.ndarray  # (F,) s, as the cameras report them
    camera_ids: list[str]
    endpoints: dict[str, str]  # "cam0".. "hub0", "host" -> endpoint
    session_skeleton: _core.Skeleton  # the session's: estimated, the truth's (oracle), the default's (live)
    calibration: str  # "estimated", "oracle" or "live"
    calibrator: str | None = None  # live: the calibrator's endpoint (its sessions in `calibrated`)
    detect_every: tuple[int, int] = (1, 1)  # the cameras' (period, burst): high-speed mode when period > 1
    keys: Path | None = None  # the devices' CURVE key pairs (DEVICE.key, DEVICE.pub); None: streams without keys

    @property
    def calibrated(self) -> Path:
        """Where the live calibrator writes the session of its latest calibration."""
        return self.session.parent / "calibrated"

    @property
    def hub_config(self) -> Path:
        """The IMU hub's hub.toml: which simulated sensor node is which IMU."""
        return self.session.parent / "hub.toml"


def calibrate(session: Path, streams: Path, detect_every: tuple[int, int]) -> _core.Skeleton:
    """Calibrates `session` (in its own folder) from the first seconds with motion of the
    messages the edge boxes send for the stream file (mocap_edge.offline), as `mocap calibrate
    --recording` calibrates a studio's session: nothing of the truth. The estimated skeleton."""
    messages = [wire.arrived(t, m) for t, m in offline.studio_messages(streams, 0, detect_every)]
    estimated = from_messages.estimate(messages, session, window.SECONDS, "the simulated studio")
    from_messages.write_session(session.parent, session, estimated, estimated.report)
    return _core.Skeleton.from_json(estimated.skeleton_json)


def free_ports(n: int) -> list[int]:
    socks = [socket.socket() for _ in range(n)]
    for s in socks:
        s.bind(("127.0.0.1", 0))
    ports = [s.getsockname()[1] for s in socks]
    for s in socks:
        s.close()
    return ports


def _simulate(seconds: float, preset: str, cameras: int | None, rng: np.random.Generator,
              still_s: float) -> tuple[_core.Skeleton, np.ndarray, sim_take.Take, Streams]:
    """The demo motion (after standing still for still_s) simulated: its skeleton, poses, the
    take, and the take's streams with the IMUs at their own rate (IMU_RATE)."""
    skeleton, thetas, dt = demo_motion.load_motion(60.0, seconds)
    if still_s > 0:
        thetas = demo_motion.after_held_pose(thetas, thetas[min(len(thetas) - 1, round(3.0 / dt))], dt, still_s)
    config = sim_take.Config(preset=preset, cameras=cameras)
    t = sim_take.simulate_motion(skeleton, thetas, dt, config, rng)
    imu_times = np.arange(0.0, (len(thetas) - 1) * dt, 1.0 / IMU_RATE)
    quats, accs = sim_take.imu_readings(skeleton, t.imus, demo_motion.interpolate(thetas, imu_times / dt),
                                        imu_times, config, rng)
    keypoints = np.zeros((len(thetas), len(t.rig.cameras), len(t.layout), 3), np.float32)
    detected = np.array([k is not None for k in t.keypoints])
    for f, k in enumerate(t.keypoints):
        if k is not None:
            keypoints[f] = k
    streams = Streams([c.name for c in t.rig.cameras], t.layout.name,
                      np.array([[c.width, c.height] for c in t.rig.cameras]), np.round(t.times * 1e9).astype(np.int64),
                      keypoints, detected, [s.name for s in t.imus], np.round(imu_times * 1e9).astype(np.int64),
                      quats, accs)
    return skeleton, thetas, t, streams


def _calibration_files(folder: Path, calibration: str, skeleton: _core.Skeleton, t: sim_take.Take, streams: Streams,
                       preset: str) -> tuple[_core.Skeleton, str]:
    """Writes the session's skeleton and IMU set as the calibration says (the truth's, or
    the default skeleton with the IMU set's bones when it is to be estimated); the session's
    skeleton and layout file."""
    session_skeleton, imus, layout = skeleton, t.imus, str(paths.LAYOUTS / f"{t.layout.name}.json")
    if calibration in ("estimated", "live"):  # what a studio knows before the performer moves: the IMU set's bones
        session_skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
        imus = _core.load_imu_sites(str(paths.IMU_SETS[sim_take.PRESETS[preset].imus]), session_skeleton)
    (folder / "skeleton.json").write_text(session_skeleton.to_json())
    (folder / "rig.json").write_text(t.rig.to_json())
    (folder / "imus.json").write_text(json.dumps(imu_set_json(session_skeleton, imus), indent=1))
    return session_skeleton, layout


def _make_keys(folder: Path, camera_ids: list[str], endpoints: dict[str, str], inputs: list[str]) -> CurveSettings:
    """A key pair per device (the host's too) and the session's "curve" object naming them."""
    public = {}
    for device in ["host", *camera_ids, "hub0"]:
        keys.make_keypair(folder, device, force=True)
        public[device] = keys.read_secret(folder / f"{device}.key").public
    public["calibrator"] = public["host"]
    return CurveSettings(f"{folder.name}/host.key", {endpoints[d]: public[d] for d in [*camera_ids, "hub0", "calibrator"]
                                                     if endpoints[d] in inputs})


def prepare(folder: Path, seconds: float, preset: str = "hq13", cameras: int | None = None, seed: int = 0,
            calibration: str = "estimated", still_s: float = 0.0, curve: bool = False) -> Studio:
    """Simulates `seconds` of the demo motion (after standing still for still_s, if given)
    and writes the session (skeleton, told rig, IMU set, layout, prior, endpoints) and the
    stream file into `folder`; the calibration is "estimated", "oracle" or "live" (see the
    module docstring). curve: every stream authenticated and encrypted, each device with a key
    pair of its own in folder/keys (the live calibrator serves the host's)."""
    if calibration not in ("estimated", "oracle", "live"):
        raise InputError(f"calibration is 'estimated', 'oracle' or 'live', not {calibration!r}")
    folder.mkdir(parents=True, exist_ok=True)
    skeleton, thetas, t, streams = _simulate(seconds, preset, cameras, np.random.default_rng(seed), still_s)
    streams.save(folder / "streams.npz")
    (folder / "hub.toml").write_text(studio_config(streams).to_toml())
    camera_ids = streams.camera_ids
    ports = free_ports(len(camera_ids) + 3)
    endpoints = {c: f"tcp://127.0.0.1:{p}" for c, p in zip([*camera_ids, "hub0", "host", "calibrator"], ports)}
    session_skeleton, layout = _calibration_files(folder, calibration, skeleton, t, streams, preset)
    inputs = [endpoints[c] for c in [*camera_ids, "hub0", *(["calibrator"] if calibration == "live" else [])]]
    session = Session("skeleton.json", "rig.json", layout, "imus.json", inputs, endpoints["host"],
                      prior=str(paths.HOST_DATA / "prior_default.json"), sync=SyncSettings(max_wait_ms=MAX_WAIT_MS),
                      solver={} if calibration == "oracle" else {"heading_time_constant": window.HEADING_TIME_CONSTANT_S},
                      imus_calibrated=calibration != "live",
                      curve=_make_keys(folder / "keys", camera_ids, endpoints, inputs) if curve else None)
    detect_every = (sim_take.PRESETS[preset].period, sim_take.PRESETS[preset].burst)
    path = session.save(folder / "session.json")
    if calibration == "estimated":
        session_skeleton = calibrate(path, folder / "streams.npz", detect_every)
    return Studio(path, folder / "streams.npz", skeleton, thetas, t.times, camera_ids,
                  {k: v for k, v in endpoints.items() if k != "calibrator"}, session_skeleton, calibration,
                  endpoints["calibrator"] if calibration == "live" else None, detect_every,
                  folder / "keys" if curve else None)
