"""What the clips do not hold, put into a simulated take: joints bent far beyond the motion the
prior was trained on (a dancer's pointed foot, a gymnast's wrist), and a sensor that slips on
its segment mid-take (its strap turned: its readings turn with it while the calibration still
has the old mounting). `mocap eval --bend ... --slip ...`."""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap import rotations
from mocap.errors import InputError

AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


@dataclasses.dataclass(frozen=True)
class Bend:
    """Bones turned by `degrees` about `axis` (each bone's own frame, after its clip rotation),
    eased in over ramp_s from from_s and held to the end of the take."""
    bones: tuple[str, ...]
    axis: str
    degrees: float
    from_s: float = 1.0
    ramp_s: float = 1.0

    @staticmethod
    def parse(text: str) -> Bend:
        """BONE[,BONE...]:AXIS:DEGREES, e.g. foot_l,foot_r:x:90."""
        bones, axis, degrees = _fields(text, 3, "--bend", "BONE[,BONE...]:x|y|z:DEGREES, e.g. foot_l,foot_r:x:90")
        return Bend(tuple(bones.split(",")), axis, float(degrees))


@dataclasses.dataclass(frozen=True)
class Slip:
    """The sensor turns on its segment by `degrees` about `axis` (its own frame) at at_s."""
    sensor: str
    at_s: float
    axis: str
    degrees: float

    @staticmethod
    def parse(text: str) -> Slip:
        """SENSOR:AT_S:AXIS:DEGREES, e.g. forearm_l:4:z:60."""
        sensor, at_s, axis, degrees = _fields(text, 4, "--slip", "SENSOR:AT_S:x|y|z:DEGREES, e.g. forearm_l:4:z:60")
        return Slip(sensor, float(at_s), axis, float(degrees))


def _fields(text: str, count: int, flag: str, usage: str) -> list[str]:
    """The `count` ':'-separated fields of a --bend / --slip value: numbers after the first,
    the second-to-last an axis; InputError saying how to write it otherwise."""
    fields = text.split(":")
    try:
        if len(fields) != count or fields[-2] not in AXES:
            raise ValueError
        for number in fields[1:-2] + fields[-1:]:
            float(number)
    except ValueError:
        raise InputError(f"{flag} {text!r}: {usage}") from None
    return fields


def bend(thetas: np.ndarray, bone_names: list[str], b: Bend, dt: float) -> np.ndarray:
    """Poses (F, 66) with b's bones turned (theta: root translation, then a rotation vector
    per bone in bone order)."""
    out = thetas.copy()
    t = np.arange(len(thetas)) * dt
    amount = np.clip((t - b.from_s) / b.ramp_s, 0.0, 1.0) if b.ramp_s > 0 else (t >= b.from_s).astype(float)
    axis = np.array(AXES[b.axis])
    for name in b.bones:
        if name not in bone_names:
            raise InputError(f"--bend: no bone {name!r} (the skeleton's: {', '.join(bone_names)})")
        j = 3 + 3 * bone_names.index(name)
        turn = rotations.exp(np.radians(b.degrees) * amount[:, None] * axis)  # (F, 3, 3)
        out[:, j:j + 3] = rotations.log(rotations.exp(thetas[:, j:j + 3]) @ turn)
    return out


def slip(quaternions: np.ndarray, accelerations: np.ndarray, sensor_names: list[str], times: np.ndarray,
         s: Slip) -> tuple[np.ndarray, np.ndarray]:
    """IMU readings (F, M, 4) w, x, y, z and (F, M, 3) sensor frame as the slipped sensor gives
    them: from at_s its frame is turned by the slip (orientation R -> R S, acceleration a ->
    S^T a)."""
    if s.sensor not in sensor_names:
        raise InputError(f"--slip: no sensor {s.sensor!r} (the take's: {', '.join(sensor_names)})")
    i = sensor_names.index(s.sensor)
    turn = rotations.exp(np.radians(s.degrees) * np.array(AXES[s.axis]))
    after = times >= s.at_s
    q, a = quaternions.copy(), accelerations.copy()
    r = rotations.matrix_from_quaternion(q[after, i]) @ turn
    q[after, i] = rotations.quaternion_from_matrix(r)
    a[after, i] = a[after, i] @ turn  # S^T a, row vectors
    return q, a
