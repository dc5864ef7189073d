"""The live calibrator's policy and buffer (mocap.calibrator): when it calibrates and what it
keeps. Its run beside mocapd is tested end to end in tests/test_live.py."""

import numpy as np

from mocap import calibrator
from mocap.calibration import informative

GOOD, MIN = informative.GOOD_SCORE_DEG, informative.MIN_SCORE_DEG


def test_the_first_calibration_waits_for_motion_then_settles_for_less():
    p = calibrator.Policy(max_wait_s=30.0)
    assert not p.due(0.6, 10.0, None, np.inf)  # standing still
    assert p.due(GOOD + 1, 6.0, None, np.inf)  # moving: at once
    assert not p.due(GOOD - 5, 10.0, None, np.inf)  # moving a little: wait for more ...
    assert p.due(GOOD - 5, 31.0, None, np.inf)  # ... but not for ever
    assert not p.due(MIN - 1, 60.0, None, np.inf)  # too still to calibrate from, however long


def test_a_calibration_is_refined_when_the_motion_is_much_richer_and_not_too_often():
    p = calibrator.Policy(refine_factor=1.5, min_interval_s=20.0)
    assert not p.due(20.0, 60.0, 18.0, 30.0)  # about as rich as the window in use
    assert p.due(28.0, 60.0, 18.0, 30.0)
    assert not p.due(28.0, 60.0, 18.0, 10.0)  # the last calibration started 10 s ago


def test_without_imus_the_skeleton_comes_from_video_and_imus_that_join_later_are_calibrated():
    p = calibrator.Policy(min_interval_s=20.0)
    assert p.due(float("nan"), 5.0, None, np.inf)  # no IMU sends: video alone, at once
    assert not p.due(float("nan"), 60.0, float("nan"), 30.0)  # and nothing more while none sends
    assert not p.due(GOOD + 1, 60.0, float("nan"), 10.0)  # the hub came: not before the interval ...
    assert p.due(GOOD + 1, 60.0, float("nan"), 30.0)  # ... then with the IMUs
    assert not p.due(MIN + 1, 60.0, float("nan"), 30.0)  # once they move enough


def test_the_buffer_keeps_the_last_seconds_by_arrival():
    b = calibrator.Buffer(keep_s=2.0)
    for k in range(50):
        b.add(int(k * 0.1e9), "mocap.v1.ImuBatch", bytes([k]))
    kept = b.snapshot()
    assert len(kept) == 21 and kept[0] == ("mocap.v1.ImuBatch", bytes([29])) and kept[-1][1] == bytes([49])
