"""Where each IMU sits on its segment, from its accelerometer against the solved motion.

The sensor at offset o (bone frame) from its bone's origin moves as x(t) = p(t) + G(t) o, so
its world acceleration x''(t) = p''(t) + G''(t) o is linear in o. The accelerometer gives it
as Rs(t) f(t) - g (Rs: the sensor's world orientation, calibrated reading; f: specific force,
sensor frame). Over the calibration window, with p and G from a solve that does not use the
accelerations, least squares for o:   G''(t) o = Rs f - g - p''(t).
The solved positions are noisy (centimetres, frame to frame): both sides are smoothed by the
same Gaussian (SMOOTH_FRAMES) before differencing, which keeps the relation exact. A ridge
pulls o towards the strap's usual place (half way along a limb segment, PRIOR_M), so a sensor
that barely turned in the window keeps that, and a robust second pass drops frames whose
residual is far above the median.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap import _core, rotations

SMOOTH_FRAMES = 4.0  # Gaussian sigma, frames
PRIOR_M = 0.1  # ridge: sigma of the offset around the usual place, m
ACCEL_SIGMA = 1.0  # m/s^2: the smoothed acceleration's typical misfit (the ridge's scale)
MIN_FRAMES = 60


@dataclasses.dataclass
class ImuPosition:
    offset: np.ndarray  # (3,) m, bone frame
    frames: int  # frames used (0: the usual place, nothing estimated)
    residual_ms2: float  # median misfit of the smoothed accelerations, m/s^2


def usual_place(skeleton: _core.Skeleton, bone: int) -> np.ndarray:
    """Half way along a segment with one child (a limb), else the bone's origin."""
    children = [c for c, p in enumerate(skeleton.parents) if p == bone]
    return 0.5 * np.asarray(skeleton.offsets)[children[0]] if len(children) == 1 else np.zeros(3)


def _smooth(x: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing along axis 0, 'valid' part only (3 sigma trimmed at both ends)."""
    r = int(np.ceil(3 * sigma))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    flat = x.reshape(len(x), -1)
    out = np.stack([np.convolve(flat[:, j], k, mode="valid") for j in range(flat.shape[1])], axis=1)
    return out.reshape((len(out),) + x.shape[1:])


def longest_run(ok: np.ndarray) -> tuple[int, int]:
    """[lo, hi) of the longest run of True."""
    best, start = (0, 0), None
    for i, v in enumerate(np.append(ok, False)):
        if v and start is None:
            start = i
        elif not v and start is not None:
            best = max(best, (start, i), key=lambda r: r[1] - r[0])
            start = None
    return best


def _second_difference(x: np.ndarray, dt: float) -> np.ndarray:
    return (x[2:] - 2 * x[1:-1] + x[:-2]) / (dt * dt)


def estimate(skeleton: _core.Skeleton, site: _core.ImuSite, thetas: np.ndarray, times: np.ndarray,
             quaternions: np.ndarray, accelerations: np.ndarray, gravity: float = 9.80665) -> ImuPosition:
    """The offset of one IMU (mount and reference calibrated) from consecutive frames' poses
    thetas (T, 66) at times (T,), and its readings there: quaternions (T, 4) w, x, y, z and
    accelerations (T, 3) sensor frame."""
    prior = usual_place(skeleton, site.bone)
    ok = np.isfinite(quaternions).all(axis=1) & np.isfinite(accelerations).all(axis=1) & np.isfinite(thetas).all(axis=1)
    lo, hi = longest_run(ok)  # the filter needs an unbroken run
    if hi - lo < MIN_FRAMES:
        return ImuPosition(prior, 0, float("nan"))
    thetas, times, quaternions, accelerations = thetas[lo:hi], times[lo:hi], quaternions[lo:hi], accelerations[lo:hi]
    dt = float(np.median(np.diff(times)))
    fk = [skeleton.forward_kinematics(t) for t in thetas]
    g = np.array([r[site.bone] for r, _ in fk])
    p = np.array([x[site.bone] for _, x in fk])
    sensor_world = np.asarray(site.reference) @ rotations.matrix_from_quaternion(quaternions)
    accel_world = np.einsum("tij,tj->ti", sensor_world, accelerations) - np.array([0.0, 0.0, gravity])
    a = _second_difference(_smooth(g, SMOOTH_FRAMES), dt)  # (T', 3, 3)
    b = _smooth(accel_world, SMOOTH_FRAMES)[1:-1] - _second_difference(_smooth(p, SMOOTH_FRAMES), dt)
    use = np.ones(len(a), bool)
    lam = (ACCEL_SIGMA / PRIOR_M) ** 2
    for _ in range(2):
        aa, bb = a[use].reshape(-1, 3), b[use].reshape(-1)
        offset = np.linalg.solve(aa.T @ aa + lam * np.eye(3), aa.T @ bb + lam * prior)
        misfit = np.linalg.norm(np.einsum("tij,j->ti", a, offset) - b, axis=1)
        use = misfit <= 3.0 * np.median(misfit)
    return ImuPosition(offset, int(use.sum()), float(np.median(misfit[use])))
