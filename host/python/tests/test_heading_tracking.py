"""Heading tracking (SolverOptions.heading_time_constant) with a window calibration: on a 20 s
take whose IMU headings drift as magnetometers do indoors (5 deg/sqrt(min), ten times the
default simulation's), the headings in use end closer to the truth with tracking than with
the window's alone, and the joint centres are no worse."""

import dataclasses

import numpy as np
import pytest

from mocap.calibration import window
from mocap.eval import metrics
from mocap.eval import simulated as evaluation
from mocap.sim import demo_motion, imu
from mocap.sim import messages as sim_messages
from mocap.sim import take as sim_take


@pytest.fixture(scope="module")
def drifting():
    skeleton, thetas, dt = demo_motion.load_motion(60.0, 20.0)
    config = sim_take.Config(imu=dataclasses.replace(imu.ImuErrors(), heading_drift_deg_per_sqrt_min=5.0))
    t, frames = sim_messages.delivered(sim_take.simulate_motion(skeleton, thetas, dt, config, np.random.default_rng(1)))
    return t, evaluation.estimate_calibration(t, frames)


def solve(t, c, options):
    """Joint-centre error (cm) and the heading corrections per frame (F, M) rad."""
    headings = []
    thetas, _ = evaluation.solve(t, options, c, headings)
    errors = metrics.errors(t.skeleton, t.thetas, thetas, t.times[1] - t.times[0], c.skeleton)
    return errors["joint_centres_pos_cm"], np.array(headings)


def test_tracking_keeps_drifting_headings_near_the_truth(drifting):
    t, c = drifting
    fixed_cm, fixed = solve(t, c, evaluation.options_for([]))
    tracked_cm, tracked = solve(t, c, window.solver_options())
    assert not fixed.any() and np.abs(tracked).max() > np.radians(1.0)
    last = slice(-600, None)  # the last 10 s
    before = np.median(metrics.heading_errors_deg(t, c, fixed)[last])
    after = np.median(metrics.heading_errors_deg(t, c, tracked)[last])
    # Measured: median 3.3 deg with the window's headings, 2.1 tracked; joint centres 1.99 / 2.00 cm
    # (1.987 / 2.009 since the window holds the right upper arm's heading at its accelerometer's,
    # 7.9 deg from where the window put it: its heading error is then 1.8 deg).
    assert after < 0.8 * before, (before, after)
    assert tracked_cm < fixed_cm + 0.03, (fixed_cm, tracked_cm)
