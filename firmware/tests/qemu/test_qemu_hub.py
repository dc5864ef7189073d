"""The IMU hub (mocap_edge.hub) against the firmware in QEMU: the node's UART carries the CAN
bus as SLCAN over TCP (`slcan:socket://…`, as a USB-CAN adapter would), the hub discovers the
node from its heartbeat, configures and starts it, fits its clock from the Syncs it answers,
and publishes its samples as ImuBatch — the values the firmware logged, on the hub's clock —
and the host's input path (mocapd's C++ InputPath, through the bindings) puts them into the
frames it solves with a camera box's frames. The board: firmware/boards/lm3s6965evb (node id 7)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from mocap.net import wire
from mocap_edge.hub.can_bus import CanPort
from mocap_edge.hub.config import HubConfig
from mocap_edge.hub.hub import Hub
from mocap_edge.hub.service import HubService

from test_qemu_slcan import ACC_RESOLUTION, QUAT_RESOLUTION, read_log

NODE_ID = 7
SENSOR = "lower_back"  # a sensor of the host's 6-IMU set


def test_the_hub_times_and_publishes_what_the_firmware_sampled(qemu_arm, tmp_path):
    image = qemu_arm.board_image("lm3s6965evb", "lm3s6965evb_node")
    log = tmp_path / "node_log.txt"
    qemu, bus = qemu_arm.start_slcan_node(image, log)
    published = []
    config = HubConfig({NODE_ID: SENSOR}, rate_hz=50, sync_hz=20)
    service = HubService(CanPort(bus, echoes=False), Hub(config), published.append)
    try:
        started = time.time_ns()
        service.run(lambda: False, duration_s=6.0)
    finally:
        bus.shutdown()
        qemu.close()
    batches = [m for m in published if isinstance(m, wire.ImuBatch)]
    node = service.hub.nodes[NODE_ID]
    health = [m for m in published if isinstance(m, wire.Health)][-1]
    assert health.streams[0].stream == f"imu/{SENSOR}" and health.streams[0].active
    assert node.heartbeat["fw_version_major"] == 1 and node.reply["rate_hz"] == 50 and node.reply["running"] == 1
    samples = [s for b in batches for s in b.samples]
    assert len(samples) > 50 and {s.sensor_id for s in samples} == {SENSOR}
    # Syncs sent while the emulated node boots are answered over a second late (they wait in its
    # UART's queue): counted and left out of the clock fit, nothing else is dropped.
    assert set(service.hub.dropped) <= {"sync_unknown"} and not service.bus_errors.total() and node.counts.lost == 0
    times = np.array([s.sample_time_ns for s in samples])
    sent = np.array([b.send_time_ns for b in batches for _ in b.samples])
    # On the hub's clock: increasing, each before its batch left, and running at the rate the
    # samples arrive at. (The emulated node's timer runs slower than real time, and at a rate
    # that changes with the host's load: 50 Hz of node time came 20-32 ms apart here. The fit
    # follows it; sample times are never taken from the arrivals.)
    assert np.all(np.diff(times) > 0) and np.all(times > started) and np.all(sent > times)
    half = len(times) // 2
    assert (times[-1] - times[half]) / (sent[-1] - sent[half]) == pytest.approx(1.0, abs=0.2)
    assert np.median(sent - times) < 200e6
    # The values the firmware logged, within the CAN signals' resolution (matched by counter).
    logged = by_counter(read_log(log))
    for s in samples[-20:]:
        entry = logged[s.packet_counter]
        q = np.array([s.qw, s.qx, s.qy, s.qz])
        assert abs(q @ np.array(entry.q_wxyz)) == pytest.approx(1.0, abs=4 * QUAT_RESOLUTION)
        assert [s.ax, s.ay, s.az] == pytest.approx(entry.acc_mps2, abs=ACC_RESOLUTION / 2)
    check_the_hosts_input_path(batches, logged)


def check_the_hosts_input_path(batches: list, logged: dict) -> None:
    """The batches as mocapd receives them (at their send times) with a camera box's frames at
    50 fps in between: the samples are what the firmware logged (to the wire's resolution), and
    every frame mocapd's input path releases once the node's filter settled has the node's
    reading, slerped to the frame's time from them."""
    from mocap import _core, paths
    from mocap.model import frames, studio

    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    sites = _core.load_imu_sites(str(paths.IMU_SETS["6"]), skeleton)
    sync = _core.SyncOptions()
    sync.max_wait_ns = 1_000_000_000  # the emulated node's UART queues its samples for up to ~0.5 s
    # its timer runs at about half of real time, slower under load: 50 Hz of node time is 40 ms
    # or more apart on the hub's clock
    sync.imu_max_gap_ns = 100_000_000
    path = _core.InputPath(studio.ring_rig(1), sites, _core.KeypointLayout.load(str(paths.LAYOUTS / "coco17.json"),
                                                                                skeleton), sync)
    samples = [s for b in batches for s in b.samples]
    first, last = samples[0].sample_time_ns, samples[-1].sample_time_ns
    times = list(range(first + 100_000_000, last - 200_000_000, 20_000_000))
    messages = [(b.send_time_ns, "mocap.v1.ImuBatch", b.SerializeToString()) for b in batches]
    for k, t in enumerate(times):  # the box sends each frame 5 ms after its capture
        frame = wire.KeypointFrame(camera_id="cam0", frame_index=k, capture_time_ns=t, keypoint_layout="coco17",
                                   detected=True, send_time_ns=t + 5_000_000)
        messages.append((t + 5_000_000, "mocap.v1.KeypointFrame", frame.SerializeToString()))
    synced = frames.synchronise_all(path, sorted(messages, key=lambda m: m[0]), times)
    sensor = [site.name for site in sites].index(SENSOR)
    hub_times = np.array([s.sample_time_ns for s in samples])
    sent = [np.array([s.qw, s.qx, s.qy, s.qz]) for s in samples]
    for s, q in zip(samples, sent):  # the hub's samples are the firmware's, to the wire format's resolution
        assert np.abs(q * np.sign(q[0]) - logged[s.packet_counter].q_wxyz).max() < QUAT_RESOLUTION
    settled = next(s.sample_time_ns for s in samples if not s.status & wire.ImuSample.STATUS_ORIENTATION_INVALID)
    checked = 0
    for f in synced:
        i = int(np.searchsorted(hub_times, f.time_ns))  # the logged orientations either side, slerped
        if f.time_ns < settled + 50_000_000:  # the node's filter is settling: orientations flagged invalid
            continue
        if hub_times[i] - hub_times[i - 1] > sync.imu_max_gap_ns:
            continue  # too far apart to interpolate: the host holds the nearest (the emulated timer stalls)
        assert f.imus == [sensor] and f.has_orientation == [True]
        expected = _slerp(sent[i - 1], sent[i], (f.time_ns - hub_times[i - 1]) / (hub_times[i] - hub_times[i - 1]))
        got = f.quaternions_wxyz[0] * np.sign(f.quaternions_wxyz[0] @ expected)
        assert np.abs(got - expected).max() < 1e-6  # the hub's samples slerped to the frame's time
        checked += 1
    assert checked > 20


def by_counter(entries: list) -> dict:
    """The firmware's log by sample counter, its 8-bit sequence unwrapped as the hub unwraps it."""
    out, counter = {}, None
    for entry in entries:
        counter = entry.seq if counter is None else counter + (entry.seq - counter) % 256
        out[counter] = entry
    return out


def _slerp(q0, q1, u: float) -> np.ndarray:
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    q1 = q1 if q0 @ q1 >= 0 else -q1
    angle = np.arccos(np.clip(q0 @ q1, -1.0, 1.0))
    if angle < 1e-9:
        return q0
    return (np.sin((1 - u) * angle) * q0 + np.sin(u * angle) * q1) / np.sin(angle)
