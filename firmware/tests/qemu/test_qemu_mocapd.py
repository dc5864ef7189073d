"""The whole IMU path as processes, from the firmware to the solved pose: the firmware in
QEMU sends its samples as SLCAN over TCP, the IMU hub process (`mocap_edge imu-hub --can
slcan:socket://…`) times and publishes them, a camera box process clocks the frames, and
`mocapd` solves them. The camera sees nobody (its keypoints have no confidence), so the
pelvis mocapd publishes is turned by the node's IMU alone: it must turn as the firmware's
filter said the node turned (the board's synthetic motion turns about z, about 50° peak to
peak), at the frame's time on the hub's clock.
The board: firmware/boards/lm3s6965evb (node id 7)."""

from __future__ import annotations

import json
import subprocess
import sys
import time

import numpy as np
import pytest
import zmq

from mocap import paths
from mocap.demo.play import MOCAPD
from mocap.io.session import Session, SyncSettings
from mocap.model import studio
from mocap.net import transport, wire
from mocap_edge.hub.config import HubConfig
from mocap_edge.streams import Streams

from test_qemu_hub import _slerp, by_counter
from test_qemu_slcan import QUAT_RESOLUTION, read_log

NODE_ID = 7
SENSOR = "lower_back"  # on the pelvis, mounted as the bone (the 6-IMU set)
TAKE_S = 9.0
FRAME_NS = 20_000_000  # the camera's 50 fps
# The emulated node's timer runs at about half of real time (50 Hz of node time is ~40 ms
# apart on the hub's clock): mocapd interpolates samples up to this far apart.
MAX_GAP_NS = 100_000_000


def test_mocapd_turns_the_pelvis_as_the_firmware_turned(qemu_arm, tmp_path):
    if not MOCAPD.exists():
        pytest.skip(f"{MOCAPD} is not built (make build)")
    log = tmp_path / "node_log.txt"
    poses, batches, summary = _run_take(qemu_arm, tmp_path, log)

    samples = [s for b in batches for s in b.samples if s.sensor_id == SENSOR]
    assert len(samples) > 100, f"{len(samples)} samples reached mocapd's hub subscription"
    logged = by_counter(read_log(log))  # the hub published what the firmware sampled
    hub_q = np.array([[s.qw, s.qx, s.qy, s.qz] for s in samples])
    firmware_q = np.array([logged[s.packet_counter].q_wxyz for s in samples])
    assert np.abs(hub_q * np.sign(hub_q[:, :1]) - firmware_q * np.sign(firmware_q[:, :1])).max() < QUAT_RESOLUTION

    settled = next(s.sample_time_ns for s in samples if not s.status & wire.ImuSample.STATUS_ORIENTATION_INVALID)
    hub_times = np.array([s.sample_time_ns for s in samples])
    checked, errors, yaws = 0, [], []
    for pose in poses:
        t = pose.capture_time_ns
        i = int(np.searchsorted(hub_times, t))
        if t < settled + 100_000_000 or not 0 < i < len(hub_times) or hub_times[i] - hub_times[i - 1] > MAX_GAP_NS:
            continue  # the filter settling; the emulated timer stalled
        assert list(pose.imus) == [SENSOR] and not pose.cameras
        expected = _slerp(hub_q[i - 1], hub_q[i], (t - hub_times[i - 1]) / (hub_times[i] - hub_times[i - 1]))
        pelvis = pose.joints[0]
        got = np.array([pelvis.qw, pelvis.qx, pelvis.qy, pelvis.qz])
        errors.append(np.degrees(2 * np.arccos(min(1.0, abs(float(got @ expected))))))
        yaws.append(np.degrees(2 * np.arctan2(got[3], got[0])))
        checked += 1
    assert checked > 100, f"{checked} frames after the filter settled, of {len(poses)} published"
    assert np.ptp(yaws) > 20  # the node did turn during the take
    # Nothing else constrains the pelvis' rotation: the solve gives the IMU's (measured: under
    # 0.0001° at every frame), and a frame timed 10 ms off would be up to 0.35° away.
    p99 = np.percentile(errors, 99)
    assert p99 < 0.02, f"{checked} frames: pelvis vs the firmware's orientation p99 {p99:.4f}°, max {max(errors):.4f}°"
    assert not summary["dropped"], summary


def _run_take(qemu_arm, folder, log) -> tuple[list, list, dict]:
    """The QEMU node, the hub process on its SLCAN port, a camera box and mocapd for TAKE_S:
    mocapd's PoseFrames, the hub's ImuBatches (subscribed beside mocapd) and mocapd's exit line."""
    hub_ep, camera_ep, host_ep = (f"tcp://127.0.0.1:{qemu_arm.free_tcp_port()}" for _ in range(3))
    session = _session(folder, [camera_ep, hub_ep], host_ep)
    (folder / "hub.toml").write_text(HubConfig({NODE_ID: SENSOR}, rate_hz=50, sync_hz=20).to_toml())
    streams = _camera_seeing_nobody(folder / "camera.npz")
    qemu, port = qemu_arm.start_slcan_qemu(qemu_arm.board_image("lm3s6965evb", "lm3s6965evb_node"), log)
    start_ns = time.time_ns() + 1_000_000_000
    processes = []
    context = zmq.Context.instance()
    poses_sub = transport.subscriber(context, [host_ep])
    hub_sub = transport.subscriber(context, [hub_ep])
    try:
        processes.append(subprocess.Popen([str(MOCAPD), str(session), "--duration", str(TAKE_S + 4.0), "--quiet"],
                                          stdout=subprocess.PIPE, text=True))
        processes.append(subprocess.Popen(
            [sys.executable, "-m", "mocap_edge", "imu-hub", "--can", f"slcan:socket://127.0.0.1:{port}",
             "--config", str(folder / "hub.toml"), "--bind", hub_ep, "--duration", str(TAKE_S + 3.0)]))
        processes.append(subprocess.Popen(
            [sys.executable, "-m", "mocap_edge", "camera", "--source", f"sim:{streams}", "--camera", "cam0",
             "--bind", camera_ep, "--start-ns", str(start_ns)]))
        poses, batches = _collect(processes[0], poses_sub, hub_sub)
        summary = json.loads(processes[0].stdout.read().strip().splitlines()[-1])
    finally:
        for p in processes:
            if p.poll() is None:
                p.terminate()
            p.wait(timeout=10)
        qemu.close()
        poses_sub.close()
        hub_sub.close()
    return poses, batches, summary


def _session(folder, inputs: list[str], output: str):
    """One camera (the ring's), the 6-IMU set of which only the node's sensor exists, its
    mounting known: mocapd's session, waiting up to 2 s for a frame's inputs (the emulated
    node's UART queues its samples for up to ~0.5 s on an idle machine) and interpolating
    between its slow samples."""
    (folder / "rig.json").write_text(studio.ring_rig(1).to_json())
    session = Session(str(paths.DEFAULT_SKELETON), "rig.json", str(paths.LAYOUTS / "coco17.json"),
                      str(paths.IMU_SETS["6"]), inputs, output, prior=str(paths.HOST_DATA / "prior_default.json"),
                      sync=SyncSettings(max_wait_ms=2000.0, imu_max_gap_ms=MAX_GAP_NS * 1e-6), solver={}, imus_calibrated=True)
    return session.save(folder / "session.json")


def _camera_seeing_nobody(path):
    """A stream file for camera cam0 of ring_rig(1): TAKE_S of 50 fps frames whose
    keypoints have no confidence (the box's detector runs and finds nobody)."""
    frames = int(TAKE_S * 1e9 // FRAME_NS)
    Streams(["cam0"], "coco17", np.array([[1920, 1080]]), np.arange(frames, dtype=np.int64) * FRAME_NS,
            np.zeros((frames, 1, 17, 3), np.float32), np.ones(frames, bool), [], np.zeros(0, np.int64),
            np.zeros((0, 0, 4)), np.zeros((0, 0, 3))).save(path)
    return path


def _collect(host: subprocess.Popen, poses_sub: zmq.Socket, hub_sub: zmq.Socket) -> tuple[list, list]:
    """mocapd's PoseFrames and the hub's ImuBatches until mocapd exits."""
    poses, batches = [], []
    poller = zmq.Poller()
    poller.register(poses_sub, zmq.POLLIN)
    poller.register(hub_sub, zmq.POLLIN)
    while host.poll() is None:
        for sock, _ in poller.poll(200):
            msg = wire.decode(sock.recv_multipart())
            if isinstance(msg, wire.PoseFrame):
                poses.append(msg)
            elif isinstance(msg, wire.ImuBatch):
                batches.append(msg)
    return poses, batches
