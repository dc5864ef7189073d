"""What the calibration needs of the IMUs: their readings at the video frames' times."""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap import rotations
from mocap.calibration import imus as imu_calibration


@dataclasses.dataclass
class ImuReadings:
    """What the calibration needs of the IMUs: orientations at the video frames."""
    names: list[str]
    bones: list[int]  # skeleton bone index per sensor
    quaternions: np.ndarray  # (F, M, 4) w, x, y, z: sensor -> the sensor's own reference (NaN: none)
    accelerations: np.ndarray | None = None  # (F, M, 3) m/s^2, sensor frame, gravity's reaction (NaN: none)

    def tail(self, first: int) -> ImuReadings:
        """The readings from frame `first` on."""
        return dataclasses.replace(self, quaternions=self.quaternions[first:],
                                   accelerations=None if self.accelerations is None else self.accelerations[first:])


def readings_at(times: np.ndarray, sensors: list[tuple[str, int, np.ndarray, np.ndarray, np.ndarray]]) -> ImuReadings:
    """ImuReadings at the video frames' `times` from each sensor's (name, bone, sample times,
    quaternions (N, 4) w first, accelerations (N, 3)): orientations slerped, accelerations
    interpolated, NaN before a sensor's first sample and after its last."""
    quats = np.full((len(times), len(sensors), 4), np.nan)
    accs = np.full((len(times), len(sensors), 3), np.nan)
    for i, (_, _, t, q, a) in enumerate(sensors):
        inside = (times >= t[0]) & (times <= t[-1])
        quats[inside, i] = rotations.quaternion_from_matrix(imu_calibration.at_times(times[inside], t, q))
        accs[inside, i] = np.stack([np.interp(times[inside], t, a[:, k]) for k in range(3)], axis=1)
    return ImuReadings([s[0] for s in sensors], [s[1] for s in sensors], quats, accs)
