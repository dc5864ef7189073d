"""Simulated body-worn IMUs (Xsens MTw-like), from the true motion.

Orientation = true sensor orientation, then errors in the world frame (z up: heading):
white noise at the MTw dynamic spec (roll/pitch 0.75 deg, heading 1.5 deg RMS), a slow
heading drift (random walk, 0.5 deg/sqrt(min)), and soft-tissue wobble: a rotation of
0.3 deg per m/s^2 of the site's acceleration, about the axis normal to it and the bone.
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
    heading_drift_deg_per_sqrt_min: float = 0.5
    wobble_deg_per_ms2: float = 0.3
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
    measured = sensor_world.copy()
    if errors.random:
        noise = np.radians(rng.normal(size=(f, m, 3)) * [errors.roll_pitch_deg, errors.roll_pitch_deg, errors.heading_deg])
        minutes = np.diff(times, prepend=times[0]) / 60.0
        steps = rng.normal(size=(f, m)) * np.sqrt(minutes)[:, None]
        noise[..., 2] += np.radians(errors.heading_drift_deg_per_sqrt_min) * np.cumsum(steps, axis=0)
        axis = np.cross(bone_axis, accel_world)
        norm = np.linalg.norm(axis, axis=-1, keepdims=True)
        wobble = np.where(norm > 1e-9, axis / np.maximum(norm, 1e-9), 0.0) * np.radians(
            errors.wobble_deg_per_ms2) * np.linalg.norm(accel_world, axis=-1, keepdims=True)
        measured = rotations.exp(noise) @ rotations.exp(wobble) @ sensor_world  # errors in the world frame
    specific = accel_world + np.asarray(accel_at_rest)
    accel = np.einsum("fmji,fmj->fmi", sensor_world, specific)
    if errors.random:
        accel += rng.normal(scale=errors.accel_noise, size=accel.shape)
        accel += rng.normal(scale=errors.accel_bias, size=(1, m, 3))
    return measured, accel
