"""A take folder as the messages its cameras and IMUs would have sent (mocap.takes.messages),
and what the host's input path makes of them."""

import numpy as np
import pytest

from mocap.calibration import from_messages
from mocap.io.take_folder import read_take
from mocap.net import wire
from mocap.sim import take_out
from mocap.takes import messages


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("take")
    take_out.run(folder, seconds=1.0, preset="hq6", seed=1)
    return folder


@pytest.fixture
def take(folder):
    return read_take(folder)


def decoded(msgs):
    return [(arrival, wire.TYPES[t].FromString(p)) for arrival, t, p in msgs]


def test_every_frame_and_person_arrives_at_its_capture_time_and_samples_when_taken(take):
    take.people[0][5] = np.concatenate([take.people[0][5], take.people[0][5] + 200.0])  # a bystander
    msgs = decoded(messages.messages(take))
    arrivals = [a for a, _ in msgs]
    assert arrivals == sorted(arrivals)
    frames = [m for _, m in msgs if isinstance(m, wire.KeypointFrame)]
    assert len(frames) == take.n_frames * len(take.rig.cameras)
    assert all(a == m.capture_time_ns for a, m in msgs if isinstance(m, wire.KeypointFrame))
    first = [m for m in frames if m.camera_id == take.rig.cameras[0].name]
    assert len(first[5].persons) == 2 and first[5].detected
    assert first[7].capture_time_ns - first[0].capture_time_ns == round(7e9 / take.frame_rate)
    batches = [(a, m) for a, m in msgs if isinstance(m, wire.ImuBatch)]
    assert all(s.sample_time_ns == a for a, b in batches for s in b.samples)
    assert sum(len(b.samples) for _, b in batches) == sum(len(m.times_s) for m in take.imus)
    assert [b.sequence for _, b in batches] == list(range(len(batches)))


def test_an_invalid_acceleration_keeps_its_orientation_and_far_samples_are_left_out(take):
    imu = take.imus[0]
    imu.times_s = imu.times_s - 0.5  # starts 0.5 s before the video: only its last 0.1 s of that is sent
    invalid = int(np.searchsorted(imu.times_s, 0.0))
    imu.accelerations[invalid] = np.nan
    samples = [s for _, m in decoded(messages.messages(take)) if isinstance(m, wire.ImuBatch)
               for s in m.samples if s.sensor_id == imu.sensor]
    kept = imu.times_s >= -messages.IMU_MARGIN_S - 1e-9
    assert 0 < len(samples) == kept.sum() < len(imu.times_s)
    origin = messages.start_ns(take)
    assert min(s.sample_time_ns for s in samples) == origin + round(imu.times_s[kept][0] * 1e9) > 0
    flagged = [s for s in samples if s.status]
    assert len(flagged) == 1 and flagged[0].status == wire.ImuSample.STATUS_ACCELERATION_INVALID
    assert flagged[0].sample_time_ns == origin + round(imu.times_s[invalid] * 1e9)
    assert [flagged[0].qw, flagged[0].qx] == pytest.approx(imu.quaternions[invalid, :2])


def test_the_host_synchronises_them_into_the_takes_frames(take, tmp_path):
    for people in take.people:  # frame 3: detection ran and found nobody, in every camera
        people[3] = people[3][:0]
    session = messages.write_session(take, tmp_path / "session")
    synced = from_messages.synchronised(messages.messages(take), session, "take")
    assert synced.data.frames == take.n_frames and not synced.dropped
    assert np.allclose(synced.data.times, np.arange(take.n_frames) / take.frame_rate, atol=1e-9)
    assert synced.data.readings.names == [m.sensor for m in take.imus]
    assert synced.data.detected.all() and not synced.data.detections[3, ..., 2].any()
    assert synced.data.detections[4, ..., 2].any()
    # 100 Hz samples slerped to 60 Hz frames: each reading between its two samples' orientations
    assert np.isfinite(synced.data.readings.quaternions).all()
