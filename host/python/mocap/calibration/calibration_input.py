"""What the calibration reads of a take: the subject's keypoints per camera at each frame,
the IMU readings at the same frames, and which frames the detector ran on.

Built from the host's synchronised frames (`from_frames`: the frames mocapd would solve,
through the C++ InputPath — calibration from a recording or the live streams), or from a
simulated take's arrays (`mocap.eval`, the demo's studio, take folders) whose frames are
already aligned.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap.calibration.readings import ImuReadings


@dataclasses.dataclass
class CalibrationInput:
    detections: np.ndarray  # (F, C, K, 3) the subject's keypoints x, y (px), confidence (0: not seen)
    times: np.ndarray  # (F,) s, from the first frame
    layout: str  # the keypoint layout's name
    readings: ImuReadings | None  # None: no IMU
    detected: np.ndarray  # (F,) bool: the detector ran on the frame (HS runs it on some frames only)
    first_time_ns: int = 0  # the first frame's capture time on the studio's clock

    def __post_init__(self):
        if len(self.times) != len(self.detections) or len(self.detected) != len(self.times):
            raise ValueError(f"{len(self.times)} times, {len(self.detections)} detections and "
                             f"{len(self.detected)} detected flags: one per frame each")
        if self.readings is not None and len(self.readings.quaternions) != len(self.times):
            raise ValueError(f"IMU readings for {len(self.readings.quaternions)} frames, not {len(self.times)}")

    @property
    def frames(self) -> int:
        return len(self.times)

    def tail(self, first: int) -> CalibrationInput:
        """The frames from `first` on (times keep their origin)."""
        return dataclasses.replace(self, detections=self.detections[first:], times=self.times[first:],
                                   readings=None if self.readings is None else self.readings.tail(first),
                                   detected=self.detected[first:])

    def without_imus(self) -> CalibrationInput:
        return dataclasses.replace(self, readings=None)

    @classmethod
    def from_arrays(cls, detections: np.ndarray, times: np.ndarray, layout: str, readings: ImuReadings | None,
                    detected: np.ndarray | None = None) -> CalibrationInput:
        """Aligned arrays (detected: default every frame)."""
        detected = np.ones(len(times), bool) if detected is None else np.asarray(detected, bool)
        return cls(np.asarray(detections, float), np.asarray(times, float), layout, readings, detected)
