"""The window calibration's use of a calibration pose (mocap.calibration.window): a T-pose
held at the start of a take is found from the video alone, and tying those frames to the
rest pose pins what motion alone leaves to the prior (the mountings' twist)."""

import numpy as np
import pytest

from mocap import demo_motion
from mocap import eval as evaluation
from mocap.calibration import window
from mocap.sim import take as sim_take


def t_pose_then_motion(seconds: float = 5.0):
    """A take of the demo motion after 1 s of T-pose and a 0.5 s blend into the motion."""
    skeleton, thetas, dt = demo_motion.load_motion(60.0, seconds)
    prefix = np.zeros((90, thetas.shape[1]))
    prefix[:, :6] = thetas[0, :6]  # where the motion starts, facing its way
    prefix[60:, 6:] = np.linspace(0.0, 1.0, 30)[:, None] * thetas[0, 6:]
    return sim_take.simulate_motion(skeleton, np.vstack([prefix, thetas]), dt, sim_take.Config(),
                                    np.random.default_rng(2))


@pytest.fixture(scope="module")
def take():
    return t_pose_then_motion()


def calibrated(t, use_t_pose: bool):
    c = window.estimate(t.rig, np.array([k if k is not None else np.zeros((8, 33, 3)) for k in t.keypoints]),
                        t.times, t.layout.name,
                        window.ImuReadings([s.name for s in t.imus], [s.bone for s in t.imus], t.quaternions,
                                           t.accelerations), use_t_pose=use_t_pose)
    solved, _ = evaluation.solve(t, evaluation.options_for([]), c)
    errors = evaluation.errors(t.skeleton, t.thetas, solved, 1 / 60, c.skeleton)
    mounts = [e["mount_deg"] for e in evaluation.calibration_errors(t, c)["imus"].values()]
    return c, errors, np.median(mounts)


def test_a_held_t_pose_is_found_and_pins_the_mountings(take):
    without, e0, m0 = calibrated(take, use_t_pose=False)
    with_pose, e1, m1 = calibrated(take, use_t_pose=True)
    assert without.report["t_pose_frames"] == 0 and with_pose.report["t_pose_frames"] >= 15
    # Measured (6.5 s take): mountings median 13.8 -> 3.7 deg, bone orientations 14.5 -> 7.7
    # deg, joint centres 2.18 -> 1.65 cm.
    assert m1 < 0.4 * m0, (m0, m1)
    assert e1["ori_error_deg"] < e0["ori_error_deg"] - 5.0, (e0["ori_error_deg"], e1["ori_error_deg"])
    assert e1["joint_centres_pos_cm"] < e0["joint_centres_pos_cm"]


def test_no_t_pose_is_found_in_motion(take):
    skeleton = take.skeleton
    moving = take.thetas[120:360]  # the demo motion itself
    assert len(window.t_pose_frames(skeleton, moving, take.times[120:360])) == 0
    # The truth's own T-pose (the first second, exact and still) is found.
    found = window.t_pose_frames(skeleton, take.thetas[:120], take.times[:120])
    assert len(found) >= 45 and found.max() < 75  # measured: frames 0-51 of the 60 held
