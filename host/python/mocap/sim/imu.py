"""Simulated body-worn IMUs (Xsens MTw-like), from the true motion.

Orientation = true sensor orientation, then errors in the world frame (z up: heading):
the MTw dynamic spec (roll/pitch 0.75 deg, heading 1.5 deg RMS) as a slowly varying
error (first-order Gauss-Markov, 2 s correlation time: the MTw's Kalman filter output is
smooth), white noise of 0.02 deg per sample, a slow heading drift (random walk, 0.5
deg/sqrt(min)), and soft-tissue wobble: the sensor housing turns on the skin by 0.3 deg
per m/s^2 of the site's acceleration, about the axis normal to it and the bone, up to 8 deg (the
accelerometer turns with it). The real MTw recordings change
by 0.002-0.017 deg (median) from one 100 Hz sample to the next at rest (`mocap imu-stats`): white
noise at the spec's 0.75-1.5 deg per frame would be fifty times too rough, and would
show as jitter no real suit has.
Acceleration = second derivative of the sensor site + gravity's reaction, in the sensor
frame, + white noise 0.03 m/s^2 per axis + a constant bias per sensor and axis drawn
with 0.05 m/s^2 RMS. The noise and bias figures come from the real recordings
(`mocap imu-stats`: handheld sensor at rest 0.026-0.054 m/s^2 per axis, |a| - g of
-0.06 m/s^2; Xsens MTw at the quietest 0.5 s of the walk 0.013-0.049 m/s^2).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap import rotations


@dataclasses.dataclass(frozen=True)
class ImuErrors:
    roll_pitch_deg: float = 0.75
    heading_deg: float = 1.5
    correlation_s: float = 2.0  # of the spec error (Gauss-Markov)
    white_deg: float = 0.02  # per sample, each axis
    heading_drift_deg_per_sqrt_min: float = 0.5
    wobble_deg_per_ms2: float = 0.3
    wobble_max_deg: float = 8.0  # the skin gives way so far
    accel_noise: float = 0.03  # m/s^2 per axis
    accel_bias: float = 0.05  # m/s^2 RMS per axis
    random: bool = True


def corrupt(sensor_world: np.ndarray, accel_world: np.ndarray, bone_axis: np.ndarray, times: np.ndarray,
            errors: ImuErrors, rng: np.random.Generator, accel_at_rest=(0.0, 0.0, 9.80665)):
    """Measured orientations (F, M, 3, 3, world) and sensor-frame accelerations (F, M, 3).

    sensor_world: true sensor orientations (F, M, 3, 3); accel_world: true site
    accelerations (F, M, 3) without gravity; bone_axis: (F, M, 3) unit bone directions.
    """
    f, m = sensor_world.shape[:2]
    housing = sensor_world.copy()  # where the sensor really points: the bone's, + wobble
    measured = sensor_world.copy()
    if errors.random:
        spec = np.radians([errors.roll_pitch_deg, errors.roll_pitch_deg, errors.heading_deg])
        noise = _gauss_markov(times, errors.correlation_s, (m, 3), rng) * spec
        noise += np.radians(errors.white_deg) * rng.normal(size=(f, m, 3))
        minutes = np.diff(times, prepend=times[0]) / 60.0
        steps = rng.normal(size=(f, m)) * np.sqrt(minutes)[:, None]
        noise[..., 2] += np.radians(errors.heading_drift_deg_per_sqrt_min) * np.cumsum(steps, axis=0)
        axis = np.cross(bone_axis, accel_world)
        norm = np.linalg.norm(axis, axis=-1, keepdims=True)
        angle = np.minimum(errors.wobble_deg_per_ms2 * np.linalg.norm(accel_world, axis=-1, keepdims=True),
                           errors.wobble_max_deg)
        wobble = np.where(norm > 1e-9, axis / np.maximum(norm, 1e-9), 0.0) * np.radians(angle)
        housing = rotations.exp(wobble) @ sensor_world
        measured = rotations.exp(noise) @ housing  # errors in the world frame
    # The accelerometer and the orientation filter share the housing: the reading is in the
    # wobbled frame, so wobble misleads E_R about the bone but not E_A about the site.
    specific = accel_world + np.asarray(accel_at_rest)
    accel = np.einsum("fmji,fmj->fmi", housing, specific)
    if errors.random:
        accel += rng.normal(scale=errors.accel_noise, size=accel.shape)
        accel += rng.normal(scale=errors.accel_bias, size=(1, m, 3))
    return measured, accel


def _gauss_markov(times: np.ndarray, tau: float, shape: tuple, rng: np.random.Generator) -> np.ndarray:
    """(F, *shape) unit-variance first-order Gauss-Markov process with correlation time tau."""
    x = np.empty((len(times), *shape))
    x[0] = rng.normal(size=shape)
    for k in range(1, len(times)):
        phi = np.exp(-max(times[k] - times[k - 1], 0.0) / tau)
        x[k] = phi * x[k - 1] + np.sqrt(1.0 - phi * phi) * rng.normal(size=shape)
    return x
