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
import struct
import zipfile
from collections.abc import Collection
from pathlib import Path

import numpy as np

MAPPED_MIN_BYTES = 1 << 20  # fields not read are mapped from the file from this size on
# what each part of the studio reads of a stream file (the rest is mapped, read where used)
CAMERA_FIELDS = ("camera_ids", "layout", "image_sizes", "frame_times_ns", "detected")
IMU_FIELDS = ("imu_ids", "imu_times_ns", "imu_quaternions", "imu_accelerations")


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
        """That camera's part, in memory of its own (not a view of the file's arrays)."""
        if camera_id not in self.camera_ids:
            raise ValueError(f"no camera {camera_id!r} in the stream file (it has {', '.join(self.camera_ids)})")
        c = self.camera_ids.index(camera_id)
        w, h = (int(v) for v in self.image_sizes[c])
        return CameraStream(camera_id, self.layout, (w, h), np.array(self.frame_times_ns, np.int64),
                            np.array(self.keypoints[:, c], np.float32), np.array(self.detected, bool))

    def save(self, path: Path) -> None:
        fields = {f.name: np.asarray(getattr(self, f.name)) for f in dataclasses.fields(self)}
        np.savez(path, **fields)

    @staticmethod
    def load(path: Path, read: Collection[str] | None = None) -> Streams:
        """The stream file at path. read: the fields read into memory (default all); the others
        are mapped from the file and read where used (an hour's take is 1.4 GB: a camera box
        reads its camera's keypoints, not every camera's and the IMUs')."""
        with np.load(path, allow_pickle=False) as z:
            values = {k: z[k] if read is None or k in read else _mapped(path, z, k) for k in z.files}
        values["camera_ids"] = [str(c) for c in values["camera_ids"]]
        values["imu_ids"] = [str(i) for i in values["imu_ids"]]
        values["layout"] = str(values["layout"])
        return Streams(**values)


def _mapped(path: Path, npz, name: str) -> np.ndarray:
    """Field `name` of the opened .npz as a read-only memory map of the file when it is stored
    uncompressed (np.savez's members are) and at least MAPPED_MIN_BYTES, else read."""
    info = npz.zip.getinfo(name + ".npy")
    if info.compress_type != zipfile.ZIP_STORED or info.file_size < MAPPED_MIN_BYTES:
        return npz[name]
    with open(path, "rb") as f:
        f.seek(info.header_offset)
        local = f.read(30)  # the member's local header: its name and extra field follow
        if local[:4] != b"PK\x03\x04":
            raise ValueError(f"field {name}: no zip member header at offset {info.header_offset}")
        f.seek(info.header_offset + 30 + sum(struct.unpack("<HH", local[26:30])))
        version = np.lib.format.read_magic(f)
        if version not in ((1, 0), (2, 0)):
            return npz[name]
        read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, fortran, dtype = read_header(f)
        if dtype.hasobject:
            raise ValueError(f"field {name} holds Python objects")
        return np.memmap(path, dtype, "r", f.tell(), shape, "F" if fortran else "C")
