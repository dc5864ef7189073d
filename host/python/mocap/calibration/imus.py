"""Each IMU's mounting on its segment and its heading, from a few seconds of ordinary motion
solved from video.

Model: the sensor's world orientation is the bone's (from the video solve) times the
mounting, and the sensor's reading is relative to its own earth frame (Z up, heading
unknown): Rz(psi) Q_t = G_t M for every frame t, with Q_t the reading (sensor -> the
sensor's earth), G_t the bone's orientation (bone -> world), M the mounting (sensor -> bone)
and psi the heading. Least squares over the frames: for a heading, the best mounting is the
rotation nearest sum_t G_t^T Rz(psi) Q_t, so the heading is found by a search over the
circle (the problem has local optima an alternation falls into). Bones the video constrains poorly (twist of sensor-less
neighbours) add noise, not bias; frames whose residual is far above the median are dropped
(a robust second pass).

Where it stands (simulated take, `host/python/tests/test_imu_calibration.py`): fed the true
bone orientations it recovers headings and mountings to 0.1-2 degrees (up to 5 at a foot);
fed a video-only solve's, 7-30 degrees — the twist of a limb about its own axis is what
video sees least. It is the start of the window calibration (mocap.calibration.window),
which solves the mountings, the headings and the poses together.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap import rotations


@dataclasses.dataclass
class ImuCalibration:
    sensor: str
    bone: str
    heading_rad: float  # the sensor's earth frame -> world: a rotation about Z
    mount: np.ndarray  # (3, 3) sensor -> bone
    residual_deg: float  # median angle between Rz(psi) Q_t and G_t M over the frames used
    frames: int


def _rz(psi: float) -> np.ndarray:
    c, s = np.cos(psi), np.sin(psi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _nearest_rotation(m: np.ndarray) -> np.ndarray:
    u, _, vt = np.linalg.svd(m)
    d = np.sign(np.linalg.det(u @ vt))
    return u @ np.diag([1.0, 1.0, d]) @ vt


# Rz(psi) = cos(psi) KC + sin(psi) KS + KZ
KC, KS, KZ = np.diag([1.0, 1.0, 0.0]), np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 0]]), np.diag([0.0, 0.0, 1.0])


def _fit(g: np.ndarray, q: np.ndarray) -> tuple[float, np.ndarray]:
    """The heading and mounting maximising sum_t trace((Rz(psi) Q_t)^T G_t M): for each
    heading the best mounting is closed-form, so the heading is searched over the circle
    (1 degree), then refined (0.01 degree)."""
    sums = [np.einsum("tji,jk,tkl->il", g, k, q) for k in (KC, KS, KZ)]  # sum G^T K Q

    def best(psi: float) -> tuple[float, np.ndarray]:
        a = np.cos(psi) * sums[0] + np.sin(psi) * sums[1] + sums[2]
        m = _nearest_rotation(a)
        return float(np.trace(m.T @ a)), m

    grid = np.radians(np.arange(0.0, 360.0, 1.0))
    psi = grid[int(np.argmax([best(p)[0] for p in grid]))]
    fine = psi + np.radians(np.arange(-1.0, 1.0, 0.01))
    psi = fine[int(np.argmax([best(p)[0] for p in fine]))]
    return float(psi), best(psi)[1]


def _residuals(g: np.ndarray, q: np.ndarray, psi: float, m: np.ndarray) -> np.ndarray:
    return np.degrees(rotations.angle_between(_rz(psi) @ q, g @ m))


def calibrate(sensor: str, bone: str, bone_world: np.ndarray, readings: np.ndarray) -> ImuCalibration:
    """bone_world (T, 3, 3) bone -> world from the video solve; readings (T, 3, 3) sensor ->
    the sensor's earth frame, at the same times."""
    best = None
    use = np.ones(len(readings), bool)
    for robust_pass in range(2):
        g, q = bone_world[use], readings[use]
        psi, m = _fit(g, q)
        r = _residuals(bone_world, readings, psi, m)
        best = ImuCalibration(sensor, bone, float(np.angle(np.exp(1j * psi))), m,
                              float(np.median(r[use])), int(use.sum()))
        if robust_pass == 0:
            use = r <= max(3.0 * np.median(r), 2.0)
    return best
