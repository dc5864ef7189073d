"""Headings the window's own accelerometers contradict (mocap.calibration.window, step 4).

Step 4 is solved a second time with each IMU's accelerometer heading (its yaw and standard
deviation, mocap.calibration.imu_position) as a prior, but where a segment's orientations
leave heading and mounting free to trade (a foot without heel or toe keypoints, a pelvis that
barely tilts) the pose prior and the mounting can still carry the solution away from it: a
foot's heading 23 degrees (7 sigma) from its accelerometer's, a pelvis's 50 (2.8 sigma), each
within 0-3 degrees of the truth on the accelerometer's side, and the solve's tracking error
on that bone 6-8 degrees where its neighbours' is 2-3. The check: a heading further from its
accelerometer's than CONTRADICTION_SIGMAS of the accelerometer's standard deviation (and
at least CONTRADICTION_FLOOR_DEG) is solved again held there (HOLD_SIGMA_DEG), the mounting
free to follow. If the sensor's orientations then fit much worse than before
(RESIDUAL_GROWTH times, the window's E_R residual), neither heading explains them: the
sensor is left out with the reason in the report, never used silently.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

CONTRADICTION_SIGMAS = 2.5
CONTRADICTION_FLOOR_DEG = 5.0
HOLD_SIGMA_DEG = 0.2
RESIDUAL_GROWTH = 2.0  # and at least RESIDUAL_SLACK_DEG more
RESIDUAL_SLACK_DEG = 1.0


def yaw_deg(reference: np.ndarray) -> float:
    """The heading (deg) of an IMU's reference frame, a turn about world z."""
    r = np.asarray(reference)
    return float(np.degrees(np.arctan2(r[1, 0], r[0, 0])))


def accelerometer_report(yaw: float, sigma: float) -> dict:
    """An IMU's accelerometer heading (rad, sigma rad; infinite sigma: none) as the report gives it."""
    if not np.isfinite(sigma):
        return {"heading_accelerometer_deg": None, "heading_accelerometer_sigma_deg": None}
    return {"heading_accelerometer_deg": float(np.degrees(yaw)), "heading_accelerometer_sigma_deg": float(np.degrees(sigma))}


def contradicted(result, accelerometer: dict[str, tuple[float, float]]) -> dict[str, dict]:
    """The sensors of a window result whose heading is further from their accelerometer's than
    the check allows: name -> (window_deg, accelerometer_deg, sigma_deg)."""
    out = {}
    for s in result.imus:
        yaw, sigma = accelerometer.get(s.name, (0.0, float("inf")))
        if not np.isfinite(sigma):
            continue
        window, told = yaw_deg(s.reference), float(np.degrees(yaw))
        apart = abs((window - told + 180.0) % 360.0 - 180.0)
        if apart > max(CONTRADICTION_SIGMAS * np.degrees(sigma), CONTRADICTION_FLOOR_DEG):
            out[s.name] = {"window_deg": window, "accelerometer_deg": told, "sigma_deg": float(np.degrees(sigma))}
    return out


def recheck(solve: Callable[[list], object], result, accelerometer: dict[str, tuple[float, float]],
            priors: list) -> tuple[object, dict, dict]:
    """The window result with every contradicted heading solved again held at its accelerometer's
    (solve(priors) -> a result from these heading priors, one (yaw rad, sigma rad) per sensor in
    result.imus order): (the result kept, what was done per sensor, the sensors left out -> why)."""
    found = contradicted(result, accelerometer)
    if not found:
        return result, {}, {}
    names = [s.name for s in result.imus]
    held = [np.array([accelerometer[n][0], np.radians(HOLD_SIGMA_DEG)]) if n in found else p
            for n, p in zip(names, priors)]
    again = solve(held)
    left_out = {}
    for name in found:
        before = float(result.imu_residual_deg[names.index(name)])
        after = float(again.imu_residual_deg[names.index(name)])
        found[name].update({"residual_deg_before": before, "residual_deg_held": after,
                            "heading_deg": yaw_deg(again.imus[names.index(name)].reference)})
        if after > max(RESIDUAL_GROWTH * before, before + RESIDUAL_SLACK_DEG):
            left_out[name] = (f"its heading came out {found[name]['window_deg']:.0f} deg, its accelerometer's "
                              f"{found[name]['accelerometer_deg']:.0f} ± {found[name]['sigma_deg']:.0f} deg, and held "
                              f"there its orientations fit {after:.1f} deg against {before:.1f}: the window "
                              "contradicts itself")
    return again, found, left_out
