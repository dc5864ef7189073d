"""Recorded input streams an edge box plays as if it were capturing them live.

A stream file (.npz) holds what cameras and IMUs would produce, times relative to the
start of the take (ns):
  camera_ids (C,) str, layout str, image_sizes (C, 2), frame_times_ns (F,),
  keypoints (F, C, K, 3) float32 pixels + confidence, detected (F,) bool (false: the
  box captured the frame but ran no detection, high-speed mode),
  imu_ids (M,) str, imu_times_ns (S,), imu_quaternions (S, M, 4) w, x, y, z,
  imu_accelerations (S, M, 3) m/s^2 sensor frame.
The simulated studio writes one (mocap.demo.studio); a real take could be converted to one. The
camera box plays one camera of it with the `sim:` frame source and keypoint model
(sources/sim.py, detect/sim.py), the IMU hub all of its IMUs.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np


@dataclasses.dataclass(frozen=True)
class CameraStream:
    """One camera's part of a stream file."""
    camera_id: str
    layout: str
    image_size: tuple[int, int]  # width, height, pixels
    frame_times_ns: np.ndarray  # (F,) int64, from the start of the take
    keypoints: np.ndarray  # (F, K, 3) float32 pixels + confidence (0: not seen)
    detected: np.ndarray  # (F,) bool



@dataclasses.dataclass
class Streams:
    camera_ids: list[str]
    layout: str
    image_sizes: np.ndarray
    frame_times_ns: np.ndarray
    keypoints: np.ndarray
    detected: np.ndarray
    imu_ids: list[str]
    imu_times_ns: np.ndarray
    imu_quaternions: np.ndarray
    imu_accelerations: np.ndarray

    def camera(self, camera_id: str) -> CameraStream:
        if camera_id not in self.camera_ids:
            raise ValueError(f"no camera {camera_id!r} in the stream file (it has {', '.join(self.camera_ids)})")
        c = self.camera_ids.index(camera_id)
        w, h = (int(v) for v in self.image_sizes[c])
        return CameraStream(camera_id, self.layout, (w, h), self.frame_times_ns.astype(np.int64),
                            self.keypoints[:, c], self.detected.astype(bool))

    def save(self, path: Path) -> None:
        fields = {f.name: np.asarray(getattr(self, f.name)) for f in dataclasses.fields(self)}
        np.savez(path, **fields)

    @staticmethod
    def load(path: Path) -> Streams:
        with np.load(path, allow_pickle=False) as z:
            values = {k: z[k] for k in z.files}
        values["camera_ids"] = [str(c) for c in values["camera_ids"]]
        values["imu_ids"] = [str(i) for i in values["imu_ids"]]
        values["layout"] = str(values["layout"])
        return Streams(**values)
