"""Which seconds a take is calibrated from (mocap.calibration.informative): the motion score
is the IMUs' tilt spread, a still start is passed over, a first window with enough motion is
kept, and IMUs that never move are left out with a reason."""

import numpy as np

from mocap import rotations
from mocap.calibration import from_messages, informative
from mocap.calibration.readings import ImuReadings
from mocap.calibration.calibration_input import CalibrationInput

RATE = 60.0


def readings(tilt_deg: np.ndarray, yaw_deg: np.ndarray | None = None, sensors: int = 3) -> np.ndarray:
    """(F, M, 4) quaternions of sensors tilted about x by tilt_deg (F,) and turned about the
    vertical by yaw_deg (F,)."""
    yaw = np.zeros_like(tilt_deg) if yaw_deg is None else yaw_deg
    r = rotations.exp(np.stack([np.zeros_like(yaw), np.zeros_like(yaw), np.radians(yaw)], axis=1)) @ \
        rotations.exp(np.stack([np.radians(tilt_deg), np.zeros_like(yaw), np.zeros_like(yaw)], axis=1))
    q = rotations.quaternion_from_matrix(r)
    return np.repeat(q[:, None], sensors, axis=1)


def test_the_score_is_the_tilt_spread_and_ignores_turning_about_the_vertical():
    t = np.arange(300) / RATE
    swing = 10.0 * np.sin(2 * np.pi * t)
    # A sinusoidal tilt of amplitude 10 deg has an RMS of 10 / sqrt(2) about its mean.
    assert abs(informative.window_score(readings(swing)) - 10.0 / np.sqrt(2)) < 0.1
    assert informative.window_score(readings(np.zeros_like(t), yaw_deg=90.0 * t)) < 1e-6
    q = readings(swing)
    q[:, 1] = np.nan  # a sensor without readings does not count
    assert np.isnan(informative.tilt_spread_deg(q)[1]) and abs(informative.window_score(q) - 7.07) < 0.1


def test_a_still_start_is_passed_over_and_a_moving_first_window_kept():
    t = np.arange(int(12 * RATE)) / RATE
    moving = np.where(t >= 6.0, 25.0 * np.sin(2 * np.pi * 0.8 * t), 0.0)  # still for 6 s, then moves
    seen = np.ones(len(t), bool)
    start, score = informative.choose_window(t, readings(moving), seen, 5.0)
    assert t[start] >= 4.0 and score >= informative.GOOD_SCORE_DEG, (t[start], score)
    moving_from_start = 25.0 * np.sin(2 * np.pi * 0.8 * t)
    assert informative.choose_window(t, readings(moving_from_start), seen, 5.0)[0] == 0
    # Windows the cameras see less than half of are not chosen, however much the IMUs move:
    # none starting after 3.5 s qualifies (the best that does starts at 3 s).
    seen[int(6 * RATE):] = False
    assert t[informative.choose_window(t, readings(moving), seen, 5.0)[0]] == 3.0


def test_the_window_ending_at_the_last_frame_is_a_candidate():
    """The live calibrator's buffer spans a little less than a whole step past the window (6 s
    at 60 Hz ends at 5.983 s): the seconds that triggered it, ending at the last frame, are
    still among the windows, not only the one starting at the first frame."""
    t = np.arange(int(6 * RATE)) / RATE
    moving = np.where(t >= 1.8, 25.0 * np.sin(2 * np.pi * 0.8 * t), 0.0)  # still for 1.8 s, then moves
    start, score = informative.choose_window(t, readings(moving), np.ones(len(t), bool), 5.0)
    assert abs(t[start] - (t[-1] - 5.0)) < 1.5 / RATE and score >= informative.GOOD_SCORE_DEG, (t[start], score)


def test_a_detector_on_some_frames_only_still_has_its_still_start_passed_over():
    """HS: the detector runs on 2 of every 8 frames; a window is seen enough when the frames it
    ran on are, not a quarter of all frames (every window would fail, and the still first
    one be kept)."""
    t = np.arange(int(12 * RATE)) / RATE
    moving = np.where(t >= 6.0, 25.0 * np.sin(2 * np.pi * 0.8 * t), 0.0)
    detected = np.arange(len(t)) % 8 < 2
    start, score = informative.choose_window(t, readings(moving), detected.copy(), 5.0, detected=detected)
    assert t[start] >= 4.0 and score >= informative.GOOD_SCORE_DEG, (t[start], score)
    seen = detected & (t < 6.0)  # out of view after 6 s: seen on too few of the frames detected
    assert t[informative.choose_window(t, readings(moving), seen, 5.0, detected=detected)[0]] == 3.0


def test_imus_that_never_move_are_left_out_with_a_reason():
    t = np.arange(int(8 * RATE)) / RATE
    q = readings(0.5 * np.sin(2 * np.pi * t))  # 0.35 deg: standing still, breathing
    det = np.zeros((len(t), 2, 17, 3))
    det[..., 2] = 1.0  # two cameras see every frame
    r = ImuReadings(["a", "b", "c"], [0, 1, 2], q)
    start, score, why = informative.calibration_window(CalibrationInput(det, t, "coco17", r, np.ones(len(t), bool)), 5.0)
    assert start == 0 and score < informative.MIN_SCORE_DEG and "too still" in why
    assert informative.calibration_window(CalibrationInput(det, t, "coco17", None, np.ones(len(t), bool)), 5.0) == (0, None, None)


def test_the_live_watch_scores_the_last_seconds_of_samples():
    """`mocap calibrate --connect` records until the IMUs moved enough in the last seconds
    (from_messages.MotionWatch over the ImuBatch messages as they arrive)."""
    from mocap.net import wire

    watch = from_messages.MotionWatch(seconds=5.0)
    assert np.isnan(watch.score())  # nothing yet
    t = np.arange(int(12 * 100)) / 100.0  # 100 Hz
    tilt = np.where(t >= 6.0, 25.0 * np.sin(2 * np.pi * 0.8 * t), 0.0)
    q = readings(tilt, sensors=2)
    scores = {}
    for k in range(0, len(t), 10):  # 10-sample batches
        batch = wire.ImuBatch(hub_id="hub0", sequence=k // 10)
        for f in range(k, k + 10):
            for i, name in enumerate(("a", "b")):
                s = batch.samples.add(sensor_id=name, sample_time_ns=int(t[f] * 1e9))
                s.qw, s.qx, s.qy, s.qz = q[f, i]
        invalid = batch.samples.add(sensor_id="a", sample_time_ns=int(t[k] * 1e9), qw=9.0)
        invalid.status = from_messages.INVALID_ORIENTATION  # flagged: not counted
        watch.add(batch)
        scores[round(t[k + 9])] = watch.score()
    assert scores[5] < 0.5 and scores[12] > informative.GOOD_SCORE_DEG, scores
    # A sensor that stopped sending (its last seconds long gone) no longer counts.
    stopped = wire.ImuBatch(hub_id="hub0", sequence=999)
    for k in range(20):
        s = stopped.samples.add(sensor_id="c", sample_time_ns=int(k * 1e7))
        s.qw, s.qx, s.qy, s.qz = q[0, 0]
    watch.add(stopped)  # still for 0.2 s at the start of the take
    assert abs(watch.score() - scores[12]) < 1e-9 and "c" not in watch.samples
