"""Where an IMU sits on its segment, from its accelerometer (mocap.calibration.imu_position),
on exact synthetic motion: the offset comes back, a segment that does not turn keeps the
strap's usual place, and a gap in the readings leaves the longest unbroken run."""

import numpy as np

from mocap import _core, paths, rotations
from mocap.calibration import imu_position

RATE = 60.0
GRAVITY = np.array([0.0, 0.0, 9.80665])


def pose(skeleton, t: float, swing: float = 0.8) -> np.ndarray:
    """The pose at time t: the root walking forward while the left arm and forearm swing."""
    theta = np.zeros(skeleton.pose_dim)
    theta[0], theta[2] = 0.8 * t, 1.0
    arm, fore = (3 + 3 * skeleton.bone_names.index(b) for b in ("upper_arm_l", "forearm_l"))
    theta[arm + 2] = swing * np.sin(2 * np.pi * 0.7 * t)
    theta[arm + 0] = 0.5 * swing * np.sin(2 * np.pi * 1.1 * t + 0.3)
    theta[fore + 2] = 0.6 * swing * (1 + np.sin(2 * np.pi * 0.9 * t))
    return theta


def motion(skeleton, frames: int, swing: float = 0.8):
    """(F, 66) poses at the frames, and the sensor's exact readings there: quaternions (F, 4)
    and accelerations (F, 3), the acceleration from the site's positions 1 ms apart."""
    h = 1e-3
    thetas, quats, accs = [], [], []
    for f in range(frames):
        t = f / RATE
        pos = []
        for dt in (-h, 0.0, h):
            rot, p = skeleton.forward_kinematics(pose(skeleton, t + dt, swing))
            pos.append(p[SITE.bone] + rot[SITE.bone] @ SITE.offset)
            if dt == 0.0:
                sensor = rot[SITE.bone] @ SITE.mount
        thetas.append(pose(skeleton, t, swing))
        quats.append(rotations.quaternion_from_matrix(np.asarray(SITE.reference).T @ sensor))
        accs.append(sensor.T @ ((pos[0] - 2 * pos[1] + pos[2]) / (h * h) + GRAVITY))
    return np.array(thetas), np.array(quats), np.array(accs)


SKELETON = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
SITE = _core.ImuSite()
SITE.name, SITE.bone = "forearm_l", SKELETON.bone_names.index("forearm_l")
SITE.mount = rotations.exp(np.array([0.2, -0.1, 0.3]))
SITE.reference = rotations.exp(np.array([0.0, 0.0, 0.7]))
SITE.offset = np.array([0.02, 0.15, 0.04])
TIMES = np.arange(300) / RATE


def test_the_offset_comes_back_from_exact_motion():
    thetas, q, a = motion(SKELETON, 300)
    placed = imu_position.estimate(SKELETON, SITE, thetas, TIMES, q, a)
    assert placed.frames > 200
    assert np.linalg.norm(placed.offset - SITE.offset) < 0.002, placed.offset  # measured 0.4 mm


def test_a_segment_that_does_not_turn_keeps_the_usual_place():
    thetas, q, a = motion(SKELETON, 300, swing=0.0)  # the body walks, the arm does not turn
    placed = imu_position.estimate(SKELETON, SITE, thetas, TIMES, q, a)
    usual = imu_position.usual_place(SKELETON, SITE.bone)
    assert np.allclose(usual, 0.5 * SKELETON.offsets[SKELETON.bone_names.index("hand_l")])
    assert np.linalg.norm(placed.offset - usual) < 0.01, placed.offset


def test_a_gap_in_the_readings_leaves_the_longest_run():
    thetas, q, a = motion(SKELETON, 300)
    q[40] = np.nan  # the first 40 frames are cut off
    a[250:] = np.nan  # and the last 50: 209 remain
    placed = imu_position.estimate(SKELETON, SITE, thetas, TIMES, q, a)
    assert 150 < placed.frames <= 209 and np.linalg.norm(placed.offset - SITE.offset) < 0.005
    q[::50] = np.nan  # no run long enough: nothing estimated
    placed = imu_position.estimate(SKELETON, SITE, thetas, TIMES, q, a)
    assert placed.frames == 0 and np.allclose(placed.offset, imu_position.usual_place(SKELETON, SITE.bone))


def test_frames_missing_from_the_readings_break_the_run():
    """A live recording under load drops late frames: the frames on both sides of the hole are
    not consecutive, and a second difference across it is no acceleration. The estimate keeps
    to the longest evenly spaced run."""
    thetas, q, a = motion(SKELETON, 300)
    kept = np.r_[0:130, 133:300]  # three frames dropped: 167 evenly spaced frames remain after
    told = _core.ImuSite()
    told.name, told.bone, told.mount, told.offset = SITE.name, SITE.bone, SITE.mount, SITE.offset
    told.reference = rotations.exp(np.array([0.0, 0.0, 0.7 + np.radians(25.0)]))
    placed = imu_position.estimate(SKELETON, told, thetas[kept], TIMES[kept], q[kept], a[kept], heading_search=True)
    assert placed.frames <= 167
    assert abs(np.degrees(placed.heading_rad - 0.7)) < 0.5, np.degrees(placed.heading_rad)
    assert np.linalg.norm(placed.offset - SITE.offset) < 0.005, placed.offset
    assert imu_position.longest_run(np.ones(len(kept), bool), TIMES[kept]) == (130, 297)


def test_the_heading_comes_back_from_the_accelerometer():
    """A reference told 25 degrees off in yaw: the accelerometer's horizontal part says by how
    much, and the offset is found with the heading it settles on."""
    thetas, q, a = motion(SKELETON, 300)
    told = _core.ImuSite()
    told.name, told.bone, told.mount, told.offset = SITE.name, SITE.bone, SITE.mount, SITE.offset
    told.reference = rotations.exp(np.array([0.0, 0.0, 0.7 + np.radians(25.0)]))
    fixed = imu_position.estimate(SKELETON, told, thetas, TIMES, q, a)
    placed = imu_position.estimate(SKELETON, told, thetas, TIMES, q, a, heading_search=True)
    assert abs(np.degrees(placed.heading_rad - 0.7)) < 0.2, np.degrees(placed.heading_rad)  # measured 0.0x
    assert np.degrees(placed.heading_sigma_rad) < 2.0
    assert np.linalg.norm(placed.offset - SITE.offset) < 0.002, placed.offset
    assert np.linalg.norm(fixed.offset - SITE.offset) > 0.01  # the wrong heading misplaces it
    assert np.isnan(fixed.heading_rad)
