"""What the calibration needs of the IMUs: their readings at the video frames' times."""

from __future__ import annotations

import dataclasses

import numpy as np


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

    def only(self, names: list[str]) -> ImuReadings:
        """The readings of the named sensors, in that order."""
        columns = [self.names.index(n) for n in names]
        return ImuReadings(list(names), [self.bones[c] for c in columns], self.quaternions[:, columns],
                           None if self.accelerations is None else self.accelerations[:, columns])
