"""What the calibration reads of a take: the subject's keypoints per camera at each frame,
the IMU readings at the same frames, and which frames the detector ran on.

Built from the host's synchronised frames (`from_frames`: the frames mocapd would solve,
through the C++ InputPath), whatever the messages came from: a recording, the live streams,
a take folder (mocap.takes.messages) or a simulated take (mocap.sim.messages).
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
    def from_frames(cls, frames: list, cameras: int, layout: str, keypoints: int,
                    imu_set: list[tuple[str, int]]) -> CalibrationInput | None:
        """The input of synchronised frames (_core.SyncedFrame, mocap.model.frames) of a rig of
        `cameras`, a layout of `keypoints`, an IMU set of (name, bone) in the InputPath's
        order; a sensor with fewer than two readings is left out (the calibration cannot place
        it). None for no frame."""
        if not frames:
            return None
        n = len(frames)
        det = np.zeros((n, cameras, keypoints, 3))
        quats, accs = np.full((n, len(imu_set), 4), np.nan), np.full((n, len(imu_set), 3), np.nan)
        for f, frame in enumerate(frames):
            if frame.cameras:  # none: nobody seen (the frame still counts, as detected or not)
                det[f, frame.cameras] = frame.keypoints
            quats[f, frame.imus] = frame.quaternions_wxyz  # NaN where the synchroniser has no reading
            accs[f, frame.imus] = frame.accelerations
        times_ns = np.array([frame.time_ns for frame in frames], dtype=np.int64)
        detected = np.array([len(frame.cameras_detected) > 0 for frame in frames])
        kept = [i for i in range(len(imu_set)) if np.isfinite(quats[:, i]).all(axis=1).sum() >= 2]
        readings = None if not kept else ImuReadings([imu_set[i][0] for i in kept], [imu_set[i][1] for i in kept],
                                                     quats[:, kept], accs[:, kept])
        return cls(det, (times_ns - times_ns[0]) * 1e-9, layout, readings, detected, int(times_ns[0]))
