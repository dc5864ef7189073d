"""The host's input path from Python (_core.InputPath, host/daemon/input_path.h): wire messages
built with mocap.net.wire become the synchronised frames mocapd solves — IMU readings slerped
to the frame time, held or left out across a gap, late frames dropped and counted, frames a box
did not detect on told apart, the subject followed past a bystander."""

import json

import numpy as np
import pytest

from mocap import _core, paths
from mocap.model import studio
from mocap.net import wire

T0 = 1_763_900_000_000_000_000
MS = 1_000_000
FRAME = 16_666_667  # 60 fps


@pytest.fixture(scope="module")
def skeleton():
    return _core.Skeleton.load(str(paths.DEFAULT_SKELETON))


@pytest.fixture(scope="module")
def layout(skeleton):
    return _core.KeypointLayout.load(str(paths.LAYOUTS / "coco17.json"), skeleton)


@pytest.fixture(scope="module")
def imus(skeleton):
    return _core.load_imu_sites(str(paths.IMU_SETS["6"]), skeleton)


@pytest.fixture(scope="module")
def rig():
    return studio.ring_rig(2)


def person(keypoints: np.ndarray) -> wire.KeypointPerson:
    """A person of (K, 3) x, y, confidence."""
    return wire.KeypointPerson(x=keypoints[:, 0], y=keypoints[:, 1], confidence=keypoints[:, 2])


def frame(camera: int, t_ns: int, persons=(), detected: bool = True) -> wire.KeypointFrame:
    return wire.KeypointFrame(camera_id=f"cam{camera}", frame_index=(t_ns - T0) // FRAME, capture_time_ns=t_ns,
                              keypoint_layout="coco17", detected=detected, persons=list(persons))


def box(x: float, y: float, size: float, confidence: float = 0.9) -> np.ndarray:
    """(17, 3) keypoints spread over a size x size box whose top-left corner is at (x, y)."""
    u = np.linspace(0.0, 1.0, 17)
    return np.stack([x + size * u, y + size * u[::-1] ** 2, np.full(17, confidence)], axis=1)


def turning(t_ns: int) -> tuple[float, ...]:
    """An IMU turning about z at 1 rad/s, accelerating (s, 0, 9.81): (qw, qx, qy, qz, ax, ay, az), s since T0."""
    s = (t_ns - T0) * 1e-9
    return np.cos(s / 2), 0.0, 0.0, np.sin(s / 2), s, 0.0, 9.81


def batch(sensor: str, t_ns: int) -> wire.ImuBatch:
    qw, qx, qy, qz, ax, ay, az = turning(t_ns)
    sample = wire.ImuSample(sensor_id=sensor, sample_time_ns=t_ns, qw=qw, qx=qx, qy=qy, qz=qz, ax=ax, ay=ay, az=az)
    return wire.ImuBatch(hub_id="hub0", sequence=(t_ns - T0) // MS, samples=[sample])


def feed(path: _core.InputPath, message, now_ns: int, tracker=None) -> tuple[bool, str]:
    return path.feed(message.DESCRIPTOR.full_name, message.SerializeToString(), now_ns, tracker)


def test_an_imu_is_slerped_to_the_frame_time(rig, layout, imus):
    path = _core.InputPath(rig, imus[:1], layout)
    t = T0 + 5 * FRAME
    for s in range(T0, t - 3 * MS + 1, 10 * MS):
        assert feed(path, batch(imus[0].name, s), s + MS) == (True, "")
    feed(path, frame(0, t, [person(box(100, 100, 300))]), t + 2 * MS)
    feed(path, frame(1, t + MS // 2), t + 3 * MS)  # trigger skew within the tolerance
    assert path.take_ready(t + 3 * MS) == []  # the IMU has not reached t yet
    feed(path, batch(imus[0].name, t + 7 * MS), t + 8 * MS)
    [f] = path.take_ready(t + 8 * MS)
    assert (f.time_ns, f.last_input_ns, f.timestamp) == (t, t + 8 * MS, 0.0)
    assert f.imus == [0] and f.has_orientation == [True] and f.has_acceleration == [True]
    expected = turning(t)
    np.testing.assert_allclose(f.quaternions_wxyz, [expected[:4]], atol=1e-9)  # slerp is exact here
    np.testing.assert_allclose(f.accelerations, [expected[4:]], atol=1e-9)
    assert f.cameras == [0] and f.keypoints.shape == (1, 17, 3)


def test_a_reading_flagged_invalid_is_nan(rig, layout, imus):
    path = _core.InputPath(rig, imus[:2], layout)
    message = batch(imus[0].name, T0)
    message.samples[0].status = wire.ImuSample.STATUS_ACCELERATION_INVALID
    message.samples.add().CopyFrom(message.samples[0])
    message.samples[1].sensor_id, message.samples[1].status = imus[1].name, wire.ImuSample.STATUS_ORIENTATION_INVALID
    feed(path, message, T0)
    feed(path, frame(0, T0), T0)
    [f] = path.flush()
    assert (f.imus, f.has_orientation, f.has_acceleration) == ([0, 1], [True, False], [False, True])
    assert np.isfinite(f.quaternions_wxyz[0]).all() and np.isnan(f.accelerations[0]).all()
    assert np.isnan(f.quaternions_wxyz[1]).all() and np.isfinite(f.accelerations[1]).all()


def test_imu_samples_further_apart_than_the_gap_are_held_nearby_and_left_out_between(rig, layout, imus):
    sync = _core.SyncOptions()
    assert (sync.imu_max_gap_ns, sync.imu_max_hold_ns) == (40 * MS, 15 * MS)
    path = _core.InputPath(rig, imus[:1], layout, sync)
    samples = [T0, T0 + 40 * MS, T0 + 90 * MS]  # 40 ms apart (interpolated), then 50 ms (not)
    for s in samples:
        feed(path, batch(imus[0].name, s), T0)
    frames = [T0 + 20 * MS, T0 + 50 * MS, T0 + 65 * MS, T0 + 80 * MS]
    for t in frames:
        for c in (0, 1):
            feed(path, frame(c, t), T0)
    released = path.take_ready(T0 + 200 * MS)
    assert [f.time_ns for f in released] == frames
    slerped, held_after, between, held_before = released
    np.testing.assert_allclose(slerped.quaternions_wxyz[0], turning(frames[0])[:4], atol=1e-9)
    np.testing.assert_allclose(held_after.quaternions_wxyz[0], turning(samples[1])[:4], atol=1e-12)
    assert between.imus == [] and between.quaternions_wxyz.shape == (0, 4)
    np.testing.assert_allclose(held_before.accelerations[0], turning(samples[2])[4:], atol=1e-12)


def test_a_frame_arriving_after_its_frame_was_released_is_dropped_and_counted(rig, layout):
    path = _core.InputPath(rig, [], layout)
    feed(path, frame(0, T0), T0 + MS)
    feed(path, frame(1, T0), T0 + MS)
    assert len(path.take_ready(T0 + MS)) == 1
    feed(path, frame(0, T0 + FRAME), T0 + FRAME + MS)
    assert path.take_ready(T0 + FRAME + 24 * MS) == []  # waiting for camera 1
    [f] = path.take_ready(T0 + FRAME + 25 * MS)  # its deadline
    assert f.cameras_clocked == [0]
    ok, why = feed(path, frame(1, T0 + FRAME), T0 + FRAME + 30 * MS)
    assert not ok and why.startswith("late_or_duplicate: cam1")
    assert path.dropped == {"late_or_duplicate": 1}
    assert [c["late"] for c in path.camera_counts] == [0, 1]
    assert [c["received"] for c in path.camera_counts] == [2, 2]
    assert path.flush() == []


def test_frames_not_detected_clock_the_solve_and_are_told_apart(rig, layout):
    path = _core.InputPath(rig, [], layout)
    subject = box(100, 100, 300)
    feed(path, frame(0, T0, [person(subject)]), T0 + MS)
    feed(path, frame(1, T0, detected=False), T0 + MS)  # HS mode: no detection on this frame
    feed(path, frame(0, T0 + FRAME), T0 + FRAME + MS)  # detected, nobody there
    feed(path, frame(1, T0 + FRAME, detected=False), T0 + FRAME + MS)
    first, second = path.flush()
    assert (first.cameras_clocked, first.cameras_detected, first.cameras) == ([0, 1], [0], [0])
    np.testing.assert_allclose(first.keypoints, [subject], atol=1e-4)  # float32 on the wire
    assert (second.cameras_clocked, second.cameras_detected, second.cameras) == ([0, 1], [0], [])
    assert second.keypoints.shape[0] == 0
    assert second.timestamp == pytest.approx(FRAME * 1e-9)


def test_the_subject_is_followed_past_a_larger_bystander(skeleton, rig, layout):
    theta = np.zeros(skeleton.pose_dim)
    theta[2] = 0.95
    subject = studio.keypoints(rig, studio.site_positions(skeleton, layout.bones, layout.offsets, theta))
    bystander = subject.copy()
    bystander[:, :, 0] += 60
    bystander[:, 0, 1] -= 200  # taller
    bystander[:, :, 2] = 1.0  # and more confident
    assert (subject[..., 2] == 1).all()
    subject[:, :, 2] = 0.8

    def first_frame(path, persons, tracker=None):
        for c in (0, 1):
            assert feed(path, frame(c, T0, [person(p[c]) for p in persons]), T0 + MS, tracker)[0]
        [f] = path.take_ready(T0 + MS)
        assert f.cameras == [0, 1]
        return f

    # Without memory or a tracker: the largest person.
    largest = first_frame(_core.InputPath(rig, [], layout), [subject, bystander])
    np.testing.assert_allclose(largest.keypoints, bystander, atol=1e-3)
    # Each camera remembers its subject: the bystander who joins is not taken.
    path = _core.InputPath(rig, [], layout)
    alone = first_frame(path, [subject])
    for k in (1, 2):
        for c in (0, 1):
            feed(path, frame(c, T0 + k * FRAME, [person(bystander[c]), person(subject[c])]), T0 + k * FRAME + MS)
        [f] = path.take_ready(T0 + k * FRAME + MS)
        np.testing.assert_allclose(f.keypoints, subject, atol=1e-3)
    # A tracker that solved the first frame (a frame's attributes are the solver's inputs) picks
    # the subject where a fresh path would take the bystander.
    tracker = _core.Solver(skeleton, rig, layout, [])
    result = tracker.solve(alone.timestamp, alone.cameras, alone.keypoints, alone.imus, alone.quaternions_wxyz,
                           alone.accelerations)
    assert result.status == "initialised" and tracker.initialised
    tracked = first_frame(_core.InputPath(rig, [], layout), [bystander, subject], tracker)
    np.testing.assert_allclose(tracked.keypoints, subject, atol=1e-3)


def test_a_session_file_gives_its_layout_and_sync(tmp_path, skeleton, rig):
    (tmp_path / "rig.json").write_text(rig.to_json())
    session = {"format": "mocap.session/1", "skeleton": str(paths.DEFAULT_SKELETON), "rig": "rig.json",
               "layout": str(paths.LAYOUTS / "coco17.json"), "imus": str(paths.IMU_SETS["6"]),
               "inputs": ["tcp://127.0.0.1:5600"], "output": "tcp://127.0.0.1:5700", "sync": {"max_wait_ms": 40}}
    (tmp_path / "session.json").write_text(json.dumps(session))
    path = _core.InputPath.from_session(str(tmp_path / "session.json"))
    assert (path.layout_name, path.keypoints, len(path.camera_counts), len(path.imu_counts)) == ("coco17", 17, 2, 6)
    feed(path, frame(0, T0), T0)
    assert path.take_ready(T0 + 39 * MS) == []  # waiting for camera 1 and the IMUs: 40 ms, not 25
    assert len(path.take_ready(T0 + 40 * MS)) == 1
    session["sync"] = {"max_wait": 40}
    (tmp_path / "session.json").write_text(json.dumps(session))
    with pytest.raises(ValueError, match="unknown sync option 'max_wait'"):
        _core.InputPath.from_session(str(tmp_path / "session.json"))


def test_the_sync_options_are_declared_once_and_read_as_mocapd_reads_them(rig, layout):
    fields = {name for name, value in vars(_core.SyncOptions).items() if isinstance(value, property)}
    assert fields == set(_core.SyncOptions.FIELDS) and len(fields) == 8
    keys = list(_core.session_sync_keys())
    assert [k.replace("_ms", "_ns") for k in keys] == [f for f in _core.SyncOptions.FIELDS if f != "max_pending_frames"]
    read = _core.SyncOptions.from_session_json(json.dumps({"max_wait_ms": 30, "imu_only_rate_hz": 100}))
    assert (read.max_wait_ns, read.imu_only_rate_hz) == (30 * MS, 100)
    assert read.stale_after_ns == _core.SyncOptions().stale_after_ns
    with pytest.raises(ValueError, match="unknown sync option 'max_wait_ns'"):
        _core.SyncOptions.from_session_json('{"max_wait_ns": 30}')
    with pytest.raises(ValueError, match="out of range"):
        _core.SyncOptions.from_session_json('{"imu_max_gap_ms": -1}')
    read.max_pending_frames = 0
    with pytest.raises(ValueError, match="out of range"):
        read.check()
    with pytest.raises(ValueError, match="out of range"):
        _core.InputPath(rig, [], layout, read)
