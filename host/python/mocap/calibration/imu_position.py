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

The same relation tells the sensor's heading (the yaw of its reference frame), which the
orientations alone do not when its segment only turns about the vertical (the pelvis, the
head of an upright performer: heading and mounting trade there). The accelerometer's
horizontal part turns with the heading: with heading_search, the heading is searched over the
circle (the offset closed-form for each), and its standard deviation comes from the cost's
curvature, widened for the smoothing's correlated residuals (CORRELATED_FRAMES).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap import _core, rotations

SMOOTH_FRAMES = 4.0  # Gaussian sigma, frames
PRIOR_M = 0.1  # ridge: sigma of the offset around the usual place, m
ACCEL_SIGMA = 1.0  # m/s^2: the smoothed acceleration's typical misfit (the ridge's scale)
MIN_FRAMES = 60
GAP_STEPS = 1.5  # a step this many times the median one: frames are missing there
# The residuals of Gaussian-smoothed series are correlated over about 2 sqrt(pi) sigma
# frames: the heading's variance from the curvature is widened by as much.
CORRELATED_FRAMES = 2.0 * np.sqrt(np.pi) * SMOOTH_FRAMES
MIN_HEADING_SIGMA = np.radians(1.0)


@dataclasses.dataclass
class ImuPosition:
    offset: np.ndarray  # (3,) m, bone frame
    frames: int  # frames used (0: the usual place, nothing estimated)
    residual_ms2: float  # median misfit of the smoothed accelerations, m/s^2
    heading_rad: float = float("nan")  # heading_search: the reference's yaw (world z), rad
    heading_sigma_rad: float = float("nan")  # and its standard deviation


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


def longest_run(ok: np.ndarray, times: np.ndarray | None = None) -> tuple[int, int]:
    """[lo, hi) of the longest run of True; with times, a step longer than GAP_STEPS of the
    median step (frames dropped on the way: a second difference across it is no acceleration)
    breaks a run too."""
    ok = np.asarray(ok, dtype=bool)
    starts = np.zeros(len(ok), dtype=bool)  # a frame after a gap begins a new run
    if times is not None and len(times) > 1:
        steps = np.diff(times)
        starts[1:] = steps > GAP_STEPS * np.median(steps)
    best, start = (0, 0), None
    for i, v in enumerate(np.append(ok, False)):
        if start is not None and (not v or (i < len(ok) and starts[i])):
            best = max(best, (start, i), key=lambda r: r[1] - r[0])
            start = None
        if v and start is None:
            start = i
    return best


def _second_difference(x: np.ndarray, dt: float) -> np.ndarray:
    return (x[2:] - 2 * x[1:-1] + x[:-2]) / (dt * dt)


def _rz(psi: float) -> np.ndarray:
    c, s = np.cos(psi), np.sin(psi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class _Fit:
    """G''(t) o = Rz(d) R0 Rq(t) f(t) - g - p''(t), smoothed, for a turn d of the reference R0:
    the offset by ridge regression towards `prior`, over the frames in `use`."""

    def __init__(self, a: np.ndarray, specific: np.ndarray, rest: np.ndarray, prior: np.ndarray):
        self.a, self.specific, self.rest, self.prior = a, specific, rest, prior
        self.lam = (ACCEL_SIGMA / PRIOR_M) ** 2
        self.use = np.ones(len(a), bool)

    def solve(self, turn: float) -> tuple[float, np.ndarray, np.ndarray]:
        """(cost, offset, per-frame misfit) for the turn d (rad)."""
        b = self.specific @ _rz(turn).T - self.rest
        aa, bb = self.a[self.use].reshape(-1, 3), b[self.use].reshape(-1)
        offset = np.linalg.solve(aa.T @ aa + self.lam * np.eye(3), aa.T @ bb + self.lam * self.prior)
        misfit = np.linalg.norm(np.einsum("tij,j->ti", self.a, offset) - b, axis=1)
        return float((misfit[self.use] ** 2).sum() + self.lam * np.sum((offset - self.prior) ** 2)), offset, misfit

    def best_turn(self, around: float, half_width_deg: float, step_deg: float) -> float:
        turns = around + np.radians(np.arange(-half_width_deg, half_width_deg, step_deg))
        return float(turns[int(np.argmin([self.solve(d)[0] for d in turns]))])

    def turn_sigma(self, turn: float) -> float:
        """Standard deviation of the turn from the cost's curvature (Gauss-Newton), widened."""
        h = np.radians(0.5)
        c0, cp, cm = (self.solve(turn + d)[0] for d in (0.0, h, -h))
        curvature = max((cp + cm - 2.0 * c0) / (h * h), 1e-12)
        variance = c0 / max(3 * int(self.use.sum()) - 4, 1)  # per residual
        return max(float(np.sqrt(2.0 * variance * CORRELATED_FRAMES / curvature)), MIN_HEADING_SIGMA)


def estimate(skeleton: _core.Skeleton, site: _core.ImuSite, thetas: np.ndarray, times: np.ndarray,
             quaternions: np.ndarray, accelerations: np.ndarray, gravity: float = 9.80665,
             heading_search: bool = False) -> ImuPosition:
    """The offset of one IMU (mount and reference calibrated) from consecutive frames' poses
    thetas (T, 66) at times (T,), and its readings there: quaternions (T, 4) w, x, y, z and
    accelerations (T, 3) sensor frame; with heading_search also the heading that best
    explains the accelerations (the reference turned about world z), which the offset is
    then solved with."""
    prior = usual_place(skeleton, site.bone)
    ok = np.isfinite(quaternions).all(axis=1) & np.isfinite(accelerations).all(axis=1) & np.isfinite(thetas).all(axis=1)
    lo, hi = longest_run(ok, np.asarray(times, dtype=float))  # the filter needs an unbroken, evenly spaced run
    if hi - lo < MIN_FRAMES:
        return ImuPosition(prior, 0, float("nan"))
    thetas, times, quaternions, accelerations = thetas[lo:hi], times[lo:hi], quaternions[lo:hi], accelerations[lo:hi]
    dt = float(np.median(np.diff(times)))
    fk = [skeleton.forward_kinematics(t) for t in thetas]
    g = np.array([r[site.bone] for r, _ in fk])
    p = np.array([x[site.bone] for _, x in fk])
    reference = np.asarray(site.reference)
    specific = np.einsum("ij,tjk,tk->ti", reference, rotations.matrix_from_quaternion(quaternions), accelerations)
    fit = _Fit(_second_difference(_smooth(g, SMOOTH_FRAMES), dt),  # (T', 3, 3)
               _smooth(specific, SMOOTH_FRAMES)[1:-1],
               np.array([0.0, 0.0, gravity]) + _second_difference(_smooth(p, SMOOTH_FRAMES), dt), prior)
    turn = fit.best_turn(0.0, 180.0, 2.0) if heading_search else 0.0
    for _ in range(2):  # a robust second pass
        _, offset, misfit = fit.solve(turn)
        fit.use = misfit <= 3.0 * np.median(misfit)
        if heading_search:
            turn = fit.best_turn(turn, 2.0, 0.05)
    _, offset, misfit = fit.solve(turn)
    placed = ImuPosition(offset, int(fit.use.sum()), float(np.median(misfit[fit.use])))
    if heading_search:
        turned = _rz(turn) @ reference
        placed.heading_rad = float(np.arctan2(turned[1, 0], turned[0, 0]))
        placed.heading_sigma_rad = fit.turn_sigma(turn)
    return placed
