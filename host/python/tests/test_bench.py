"""The solver on real motion: a short run of the benchmark workload, judged on accuracy."""

from mocap.eval import bench, scale_plot


def test_solver_tracks_real_motion_with_noisy_observations(shared):
    result = bench.solver(repeats=1, frames_per_clip=90)
    assert result["bench"] == "solver"
    assert result["initial_frames"] == 3 and result["frames"] == 3 * 89
    # 2 px keypoint noise, 1 degree IMU noise: the full run gives ~7.4 mm (docs/performance.md).
    assert result["mean_joint_error_mm"] < 12.0
    assert result["mean_iterations"] < 5


def test_the_scale_benchmark_solves_every_configuration_and_draws_it(shared, tmp_path):
    """From one camera and no IMUs to 32 cameras: each configuration is solved (more cameras, a
    closer solve) and the figure is drawn."""
    result = bench.scale(repeats=1, frames_per_clip=60)
    cameras = result["cameras"]
    assert sorted(cameras) == list(bench.SCALE_CAMERAS) and sorted(result["imus"]) == list(bench.SCALE_IMUS)
    assert cameras[1]["mean_joint_error_mm"] > cameras[8]["mean_joint_error_mm"] > cameras[32]["mean_joint_error_mm"]
    assert result["imus"][0]["mean_joint_error_mm"] > result["imus"][13]["mean_joint_error_mm"]
    scale_plot.plot(result, tmp_path / "scale.png")
    assert (tmp_path / "scale.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_benchmark_length_or_camera_count_it_cannot_run_is_refused():
    import subprocess
    import sys

    for args in (["--live-cameras", "8", "0"], ["--live-seconds", "nan"], ["--minutes", "-1"]):
        out = subprocess.run([sys.executable, "-m", "mocap.cli", "bench", "--only", "live", *args],
                             capture_output=True, text=True, timeout=60)
        assert out.returncode == 2 and out.stderr.startswith(f"mocap bench: {args[0]}"), out.stderr
        assert "Traceback" not in out.stderr
