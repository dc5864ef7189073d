"""What a rig calibration starts from: each camera's detections of the person in view,
undistorted to normalised image coordinates, and the 3D points they observe (one per frame
and keypoint seen by at least two cameras)."""

from __future__ import annotations

import cv2
import numpy as np

from mocap import _core
from mocap.calibration.rig.bundle import Observations
from mocap.errors import InputError

MIN_CONFIDENCE = 0.3  # detections below are not used


def person_in_view(people: list[np.ndarray], keypoints: int) -> np.ndarray:
    """(F, K, 3) of one camera: each frame's most confident person (zeros when none)."""
    out = np.zeros((len(people), keypoints, 3))
    for f, persons in enumerate(people):
        if persons.shape[1:] != (keypoints, 3):
            raise InputError(f"frame {f}: detections of {persons.shape[1:]} values, not ({keypoints}, 3)")
        if len(persons):
            out[f] = persons[int(np.argmax(persons[:, :, 2].sum(axis=1)))]
    return out


def normalised(camera: _core.Camera, pixels: np.ndarray) -> np.ndarray:
    """(N, 2) undistorted normalised coordinates of (N, 2) pixels (OpenCV's model)."""
    k = np.array([[camera.fx, 0.0, camera.cx], [0.0, camera.fy, camera.cy], [0.0, 0.0, 1.0]])
    if not len(pixels):
        return np.zeros((0, 2))
    return cv2.undistortPoints(pixels.reshape(-1, 1, 2).astype(np.float64), k,
                               np.asarray(camera.distortion, dtype=float)).reshape(-1, 2)


def observations(cameras: list[_core.Camera], detections: list[np.ndarray]) -> tuple[Observations, np.ndarray]:
    """Observations of the points (frame, keypoint) two or more cameras saw, and each point's
    (frame, keypoint). detections: per camera (F, K, 3) pixels and confidence."""
    if len(cameras) < 2:
        raise InputError(f"{len(cameras)} camera(s): a rig calibration needs two or more")
    seen = np.stack([d[:, :, 2] >= MIN_CONFIDENCE for d in detections])  # (C, F, K)
    for cam, s in zip(cameras, seen):
        if not s.any():
            raise InputError(f"camera {cam.name}: no person detected (confidence >= {MIN_CONFIDENCE}) on any frame")
    shared = seen.sum(axis=0) >= 2  # (F, K)
    if not shared.any():
        raise InputError("no keypoint of the person was seen by two cameras on the same frame")
    point_of = np.full(shared.shape, -1)
    point_of[shared] = np.arange(shared.sum())
    cam_idx, frame, kp = np.nonzero(seen & shared[None])
    stacked = np.stack(detections)
    uv = np.zeros((len(cam_idx), 2))
    for c, cam in enumerate(cameras):
        mine = cam_idx == c
        uv[mine] = normalised(cam, stacked[c, frame[mine], kp[mine], :2])
    obs = Observations(cam_idx, point_of[frame, kp], uv, stacked[cam_idx, frame, kp, 2],
                       np.array([(cam.fx + cam.fy) / 2 for cam in cameras]))
    return obs, np.argwhere(shared)


def shared_counts(obs: Observations, n_cameras: int) -> np.ndarray:
    """(C, C) points seen by both cameras of each pair."""
    members = np.zeros((obs.point.max() + 1, n_cameras), dtype=bool)
    members[obs.point, obs.camera] = True
    m = members.astype(int)
    return m.T @ m
