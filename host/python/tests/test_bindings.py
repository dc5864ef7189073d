"""The Python bindings call the same C++ code: FK, projection and the solver."""

import numpy as np
import pytest

from mocap import _core, paths, rotations
from mocap.model import studio


@pytest.fixture(scope="module")
def skeleton():
    return _core.Skeleton.load(str(paths.DEFAULT_SKELETON))


def test_forward_kinematics_matches_a_hand_computed_pose(skeleton):
    theta = np.zeros(skeleton.pose_dim)
    theta[0:3] = [1.0, 2.0, 0.9]
    theta[3:6] = [0.0, 0.0, np.pi / 2]  # root yaw 90 degrees: the left (+y) side turns to -x
    rot, pos = skeleton.forward_kinematics(theta)
    thigh = skeleton.bone_index("thigh_l")
    offset = skeleton.offsets[thigh]  # (0, 0.09, -0.02)
    np.testing.assert_allclose(pos[thigh], [1.0 - offset[1], 2.0 + offset[0], 0.9 + offset[2]], atol=1e-12)
    np.testing.assert_allclose(rot[thigh], rotations.exp(np.array([0, 0, np.pi / 2])), atol=1e-12)


def test_malformed_inputs_raise_value_errors(skeleton):
    with pytest.raises(ValueError, match="wrong size"):
        skeleton.forward_kinematics(np.zeros(5))
    with pytest.raises(ValueError, match="cannot open"):
        _core.Skeleton.load("/nonexistent.json")
    with pytest.raises(ValueError, match="orthonormal"):
        _core.PosePrior(np.zeros(60), np.ones((60, 2)), np.ones(2))


def test_solver_recovers_a_pose_from_exact_observations(skeleton):
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / "blazepose33.json"), skeleton)
    imus = _core.load_imu_sites(str(paths.IMU_SETS["13"]), skeleton)
    rig = studio.ring_rig(6)
    rng = np.random.default_rng(1)
    truth = np.zeros(skeleton.pose_dim)
    truth[0:3] = [0.1, -0.2, 0.95]
    truth[3:6] = [0.0, 0.0, 0.7]
    truth[6:] = rng.uniform(-0.25, 0.25, size=60)
    kp = studio.keypoints(rig, studio.site_positions(skeleton, layout.bones, layout.offsets, truth))
    quats, accs = studio.imu_readings(skeleton, imus, truth[None], np.zeros(1))
    solver = _core.Solver(skeleton, rig, layout, imus)
    result = solver.solve(0.0, list(range(6)), kp, list(range(len(imus))), quats[0], np.full((len(imus), 3), np.nan))
    assert result.status == "initialised", result.message
    sites_est = studio.site_positions(skeleton, layout.bones, layout.offsets, result.theta)
    sites_true = studio.site_positions(skeleton, layout.bones, layout.offsets, truth)
    assert np.abs(sites_est - sites_true).max() < 1e-3
    assert result.counts["keypoints_used"] == int((kp[..., 2] > 0).sum())
    assert result.counts["orientations_used"] == 13


def test_solver_counts_and_drops_bad_input(skeleton):
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / "coco17.json"), skeleton)
    solver = _core.Solver(skeleton, studio.ring_rig(2), layout, [])
    kp = np.full((2, 17, 3), np.nan)
    result = solver.solve(0.0, [0, 1], kp, [], np.zeros((0, 4)), np.zeros((0, 3)))
    assert result.status == "no_observations"
    assert result.counts["keypoints_invalid"] == 34
    assert np.isfinite(result.theta).all()
    with pytest.raises(ValueError, match="keypoints must be"):
        solver.solve(1.0, [0], np.zeros((2, 17, 3)), [], np.zeros((0, 4)), np.zeros((0, 3)))


def test_options_are_validated_when_replaced(skeleton):
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / "coco17.json"), skeleton)
    solver = _core.Solver(skeleton, studio.ring_rig(2), layout, [])
    options = solver.options
    options.max_iterations = 0
    with pytest.raises(ValueError, match="out of range"):
        solver.options = options
    assert solver.options.max_iterations == _core.SolverOptions().max_iterations
    options.max_iterations = 4
    solver.options = options
    assert solver.options.max_iterations == 4


def test_python_solver_uses_the_shipped_prior_unless_told_not_to(skeleton):
    from mocap.model.solver import Solver

    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / "coco17.json"), skeleton)
    rig = studio.ring_rig(4)
    theta = np.zeros(skeleton.pose_dim)
    theta[2] = 0.95
    theta[6:] = 0.3  # far from the prior's mean
    kp = studio.keypoints(rig, studio.site_positions(skeleton, layout.bones, layout.offsets, theta))
    costs = []
    for solver in (Solver(skeleton, rig, layout, []), Solver(skeleton, rig, layout, [], prior_model=None)):
        solver.set_warm_start(theta)
        costs.append(solver.solve(0.0, list(range(4)), kp, [], np.zeros((0, 4)), np.zeros((0, 3))).costs)
    assert costs[0]["pca_projection"] > 0 and costs[0]["pca_deviation"] > 0
    assert costs[1]["pca_projection"] == 0 and costs[1]["pca_deviation"] == 0
