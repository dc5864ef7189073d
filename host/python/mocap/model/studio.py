"""A studio built in code: camera rigs and exact observations of a pose sequence.

The simulated studio of the evaluation (detector and IMU error models) builds on this.
"""

from __future__ import annotations

import numpy as np

from mocap import _core, rotations


def ring_rig(cameras: int = 8, center=(0.0, 0.0), radius: float = 4.5, heights=(1.2, 2.4),
             target_height: float = 1.0, size=(1920, 1080), focal: float = 1400.0) -> _core.Rig:
    """Cameras evenly on a ring around `center`, aimed at the volume centre."""
    rig = _core.Rig()
    cams = []
    for c in range(cameras):
        a = 2.0 * np.pi * c / cameras
        h = heights[0] + (heights[1] - heights[0]) * (c % 2)
        eye = np.array([center[0] + radius * np.cos(a), center[1] + radius * np.sin(a), h])
        z = np.array([center[0], center[1], target_height]) - eye
        z /= np.linalg.norm(z)
        x = np.cross(z, [0.0, 0.0, 1.0])
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        cam = _core.Camera()
        cam.name = f"cam{c}"
        cam.width, cam.height = size
        cam.fx = cam.fy = focal
        cam.cx, cam.cy = size[0] / 2.0, size[1] / 2.0
        cam.distortion = [-0.1, 0.04, 0.0, 0.0, 0.0]
        cam.rotation = np.stack([x, y, z])
        cam.translation = -cam.rotation @ eye
        cams.append(cam)
    rig.cameras = cams
    return rig


def site_positions(skeleton: _core.Skeleton, bones, offsets, theta) -> np.ndarray:
    """(sites, 3) world positions of sites (bone, offset) at pose theta."""
    rot, pos = skeleton.forward_kinematics(theta)
    bones = np.asarray(bones)
    return pos[bones] + np.einsum("kij,kj->ki", rot[bones], np.asarray(offsets))


def keypoints(rig: _core.Rig, points: np.ndarray) -> np.ndarray:
    """(cameras, K, 3) pixels + confidence (1 where projectable and inside the image, else 0)."""
    out = np.zeros((len(rig.cameras), len(points), 3))
    for c, cam in enumerate(rig.cameras):
        px, ok = cam.project(points)
        inside = ok & (px[:, 0] >= 0) & (px[:, 0] < cam.width) & (px[:, 1] >= 0) & (px[:, 1] < cam.height)
        out[c, :, :2] = np.where(inside[:, None], px, 0.0)
        out[c, :, 2] = inside
    return out


def sensor_motion(skeleton: _core.Skeleton, imus, thetas: np.ndarray, times: np.ndarray):
    """True sensor orientations (F, M, 3, 3, sensor -> world) and site accelerations
    (F, M, 3, world, gravity not included) of a pose sequence.

    Acceleration at frame f is the second difference of the site over (f-1, f, f+1), the
    quantity the solver's E_A compares; the ends repeat their neighbours.
    """
    n, m = len(thetas), len(imus)
    sensor_world, sites = np.zeros((n, m, 3, 3)), np.zeros((n, m, 3))
    for f, theta in enumerate(thetas):
        rot, pos = skeleton.forward_kinematics(theta)
        for i, s in enumerate(imus):
            sensor_world[f, i] = rot[s.bone] @ s.mount
            sites[f, i] = pos[s.bone] + rot[s.bone] @ s.offset
    accel = np.zeros((n, m, 3))
    if n >= 3:
        h1 = (times[1:-1] - times[:-2])[:, None, None]
        h2 = (times[2:] - times[1:-1])[:, None, None]
        accel[1:-1] = 2.0 * ((sites[2:] - sites[1:-1]) / h2 - (sites[1:-1] - sites[:-2]) / h1) / (h1 + h2)
        accel[0], accel[-1] = accel[1], accel[-2]
    return sensor_world, accel


def readings(imus, sensor_world: np.ndarray, accel_world: np.ndarray, accel_at_rest=(0.0, 0.0, 9.80665)):
    """(F, M, 4) orientations (w, x, y, z, sensor -> each IMU's reference) and (F, M, 3)
    accelerometer readings (sensor frame, gravity's reaction included)."""
    reference = np.array([s.reference for s in imus])
    quats = rotations.quaternion_from_matrix(np.swapaxes(reference, -1, -2)[None] @ sensor_world)
    return quats, np.einsum("fmji,fmj->fmi", sensor_world, accel_world + np.asarray(accel_at_rest))


def imu_readings(skeleton: _core.Skeleton, imus, thetas: np.ndarray, times: np.ndarray):
    """Exact readings of a pose sequence: see sensor_motion and readings."""
    return readings(imus, *sensor_motion(skeleton, imus, thetas, times))
