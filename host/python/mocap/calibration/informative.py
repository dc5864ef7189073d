"""Which seconds of a take to calibrate from.

The window calibration (mocap.calibration.window) separates each IMU's heading from its
mounting, and a keypoint's site from the pose, only as far as the segments tilt and the
joints bend in the window. A performer who stands still for the first seconds leaves the
headings undetermined: a take of the demo motion after 5 s of standing still, calibrated
from those 5 s, is solved to 7.05 cm at the joint centres afterwards (headings 92 degrees
off, median), and to 2.29 cm calibrated from 5 s of its motion (docs/calibration.md).

A window's motion score needs no solve: per IMU, the RMS angle of gravity's direction in
the sensor frame about its mean over the window (how far the sensor tilts, from its own
readings); the window's score is the median over the IMUs. Standing still scores 0.6
degrees, walking 9-30, the balancing demo motion about 21.
"""

from __future__ import annotations

import numpy as np

from mocap import rotations
from mocap.calibration.calibration_input import CalibrationInput
from mocap.calibration.window import SECONDS, Calibration
from mocap.calibration.window import estimate as window_estimate

MIN_SCORE_DEG = 3.0  # below: too still to calibrate the IMUs from
# At or above: enough motion; the first such window is kept (a calibration pose held at the
# start of a take scores lower than later motion, and pins more: docs/calibration.md).
GOOD_SCORE_DEG = 15.0
MIN_SEEN = 0.5  # a window needs this fraction of its frames seen by two cameras or more


def tilt_spread_deg(quaternions: np.ndarray) -> np.ndarray:
    """(M,) per IMU, the RMS angle (deg) of gravity's direction in the sensor frame about its
    mean, from quaternions (F, M, 4) w, x, y, z sensor -> the sensor's earth frame (NaN rows:
    no reading); NaN for an IMU with fewer than two readings."""
    out = np.full(quaternions.shape[1], np.nan)
    for i in range(quaternions.shape[1]):
        q = quaternions[:, i]
        q = q[np.isfinite(q).all(axis=1)]
        if len(q) < 2:
            continue
        up = rotations.matrix_from_quaternion(q)[:, 2, :]  # the earth's z in the sensor frame: Q^T e_z
        out[i] = np.degrees(np.sqrt(np.mean(np.sum((up - up.mean(axis=0)) ** 2, axis=1))))
    return out


def window_score(quaternions: np.ndarray) -> float:
    """The median over the IMUs of tilt_spread_deg (NaN: no IMU has readings)."""
    spread = tilt_spread_deg(quaternions)
    return float(np.nanmedian(spread)) if np.isfinite(spread).any() else float("nan")


def choose_window(times: np.ndarray, quaternions: np.ndarray, seen: np.ndarray, seconds: float,
                  step_s: float = 1.0, detected: np.ndarray | None = None) -> tuple[int, float]:
    """(first frame, score) of the window of `seconds` to calibrate from, among those starting
    every step_s and the one ending at the last frame, with at least MIN_SEEN of their detected
    frames seen (seen: (F,) bool, the frames seen by two cameras or more; detected: (F,) bool,
    the frames the detector ran on, default all): the first that scores GOOD_SCORE_DEG or
    more, else the highest-scoring; the take's first window when none qualifies."""
    detected = np.ones(len(times), bool) if detected is None else detected
    best = (0, float("-inf"))
    last = max(times[0], times[-1] - seconds)
    starts = np.arange(times[0], last + 1e-9, step_s)
    if last - starts[-1] > 1e-3:  # the live calibrator's latest seconds, whatever the buffer's span
        starts = np.append(starts, last)
    for t0 in starts:
        lo, hi = np.searchsorted(times, [t0, t0 + seconds])
        if hi - lo < 2 or not detected[lo:hi].any() or seen[lo:hi].sum() < MIN_SEEN * detected[lo:hi].sum():
            continue
        score = window_score(quaternions[lo:hi])
        if np.isfinite(score) and score >= GOOD_SCORE_DEG:
            return int(lo), score
        if np.isfinite(score) and score > best[1]:
            best = (int(lo), score)
    if best[1] == float("-inf"):
        hi = int(np.searchsorted(times, times[0] + seconds))
        return 0, window_score(quaternions[:max(hi, 2)])
    return best


def calibration_window(data: CalibrationInput, seconds: float) -> tuple[int, float | None, str | None]:
    """(first frame, motion score, why the IMUs cannot be used or None) of the window to
    calibrate from: with IMUs, choose_window's; without, the first seconds."""
    if data.readings is None:
        return 0, None, None
    seen = (data.detections[..., 2] > 0).any(axis=2).sum(axis=1) >= 2
    start, score = choose_window(data.times, data.readings.quaternions, seen, seconds, detected=data.detected)
    if not np.isfinite(score) or score < MIN_SCORE_DEG:
        return 0, score, (f"the IMUs tilt by {score:.1f} deg (RMS) at most in any {seconds:g} s of the take: "
                          f"too still to calibrate their headings and mountings from (at least "
                          f"{MIN_SCORE_DEG:g} deg); solved from video alone")
    return start, score, None


def estimate(rig, data: CalibrationInput, **options) -> tuple[Calibration, float | None, str | None]:
    """window.estimate (with its keyword options) over the window calibration_window chooses,
    the IMUs left out when they are too still: (calibration, motion score, why they were)."""
    first, score, why_not = calibration_window(data, options.get("seconds", SECONDS))
    cal = window_estimate(rig, data.without_imus() if why_not else data, **{"first_frame": first, **options})
    return cal, score, why_not
