"""`mocap solve --take`: a take folder solved without oracles (the skeleton estimated, the
IMUs not yet used), on a simulated take and on Pose2Sim's real Balancing trial."""

import csv
import subprocess
import sys

import numpy as np
import pytest

from mocap import _core, balancing_take, take_solve
from mocap.demo_data import TRIAL_CACHE, TRIAL_DONE
from mocap.sim import take_out


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    folder = tmp_path_factory.mktemp("take")
    take_out.run(folder, seconds=4.0, preset="hq13", seed=3)
    out = tmp_path_factory.mktemp("solved")
    return folder, out, take_solve.solve_take(folder, out)


def test_the_estimated_skeleton_is_near_the_true_one(simulated):
    folder, out, report = simulated
    truth = _core.Skeleton.load(str(folder / "truth_skeleton.json"))
    estimated = _core.Skeleton.load(str(out / "skeleton.json"))
    error = np.abs(np.linalg.norm(estimated.offsets, axis=1) - np.linalg.norm(truth.offsets, axis=1))
    # Measured max 2.0 cm (hand), mean 0.8 cm: the simulated detector's 1-3 cm keypoint
    # offsets are not estimated yet, so the 1 cm is not reached.
    assert error.max() < 0.025 and error.mean() < 0.012, dict(zip(truth.bone_names, error.round(3)))
    assert report["imus"]["used"] is False and len(report["imus"]["sensors"]) == 13


def test_joint_centres_of_the_video_only_solve_follow_the_truth(simulated):
    folder, out, _ = simulated
    truth = _core.Skeleton.load(str(folder / "truth_skeleton.json"))
    thetas = np.load(folder / "truth_thetas.npy")
    rows = list(csv.reader(open(out / "joints.csv")))
    assert rows[0][:2] == ["frame", "time_s"] and len(rows) == len(thetas) + 1
    solved = np.array([[float(v) for v in r[2:]] for r in rows[1:]]).reshape(len(thetas), -1, 3)
    bones = [truth.bone_names.index(b) for b in take_solve.JOINTS.values()]
    expected = np.array([truth.forward_kinematics(t)[1][bones] for t in thetas])
    error = np.linalg.norm(solved - expected, axis=-1)
    assert error.mean() < 0.04, error.mean(axis=0).round(3)  # measured 3.0 cm on 6 s, seed 0


@pytest.mark.skipif(not (TRIAL_CACHE / TRIAL_DONE).is_file(), reason="the real trial is not in .cache/")
def test_pose2sims_balancing_trial_as_a_take_lands_near_its_own_3d(tmp_path):
    folder = balancing_take.write(TRIAL_CACHE, tmp_path / "take")
    report = take_solve.solve_take(folder, tmp_path / "out")
    assert report["solve"]["statuses"].get("ok", 0) == 99
    result = balancing_take.compare(TRIAL_CACHE, tmp_path / "out" / "joints.csv")
    assert result["distance_cm"] < 4.5, result  # measured 3.6 (docs/results_real.md)


def test_solve_wants_exactly_one_input(tmp_path):
    for args in ([], ["--recording", "x.mcap", "--take", str(tmp_path)]):
        out = subprocess.run([sys.executable, "-m", "mocap.cli", "solve", *args, "--out", str(tmp_path / "o")],
                             capture_output=True, text=True)
        assert out.returncode != 0 and "exactly one" in out.stderr and "Traceback" not in out.stderr
    out = subprocess.run([sys.executable, "-m", "mocap.cli", "solve", "--take", str(tmp_path / "none"), "--out",
                          str(tmp_path / "o")], capture_output=True, text=True)
    assert out.returncode != 0 and "Traceback" not in out.stderr
