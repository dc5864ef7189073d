"""The solver on real motion: a short run of the benchmark workload, judged on accuracy."""

from mocap.eval import bench


def test_solver_tracks_real_motion_with_noisy_observations(shared):
    result = bench.solver(repeats=1, frames_per_clip=90)
    assert result["bench"] == "solver"
    assert result["initial_frames"] == 3 and result["frames"] == 3 * 89
    # 2 px keypoint noise, 1 degree IMU noise: the full run gives ~7.4 mm (docs/performance.md).
    assert result["mean_joint_error_mm"] < 12.0
    assert result["mean_iterations"] < 5
