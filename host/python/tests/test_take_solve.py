"""`mocap solve --take`: a take folder solved without oracles (skeleton, IMU mountings,
headings and positions estimated from its first seconds), on a simulated take, the same take
without its IMUs, and Pose2Sim's real Balancing trial (video only)."""

import csv
import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from mocap import _core, rotations
from mocap.eval import balancing_take
from mocap.io.demo_data import TRIAL, TRIAL_CACHE, TRIAL_DONE
from mocap.io.trc import read_trc
from mocap.model.joint_centres import JOINTS
from mocap.sim import take_out
from mocap.takes import report as take_report
from mocap.takes import solve as take_solve


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    folder = tmp_path_factory.mktemp("take")
    take_out.run(folder, seconds=4.0, preset="hq13", seed=3)
    out = tmp_path_factory.mktemp("solved")
    return folder, out, take_solve.solve_take(folder, out)


@pytest.fixture(scope="module")
def video_only(simulated, tmp_path_factory):
    """The same take with its [imu] table removed."""
    folder = tmp_path_factory.mktemp("take_video") / "take"
    shutil.copytree(simulated[0], folder)
    toml = (folder / "take.toml").read_text()
    (folder / "take.toml").write_text(toml[: toml.index("[imu]")])
    out = tmp_path_factory.mktemp("solved_video")
    return folder, out, take_solve.solve_take(folder, out)


def joint_centre_errors(folder, out) -> np.ndarray:
    """(F, 13) m: joints.csv against the true joint centres."""
    truth = _core.Skeleton.load(str(folder / "truth_skeleton.json"))
    thetas = np.load(folder / "truth_thetas.npy")
    rows = list(csv.reader(open(out / "joints.csv")))
    assert rows[0][:2] == ["frame", "time_s"] and len(rows) == len(thetas) + 1
    solved = np.array([[float(v) for v in r[2:]] for r in rows[1:]]).reshape(len(thetas), -1, 3)
    bones = [truth.bone_names.index(b) for b in JOINTS.values()]
    expected = np.array([truth.forward_kinematics(t)[1][bones] for t in thetas])
    return np.linalg.norm(solved - expected, axis=-1)


def test_the_estimated_limb_lengths_are_near_the_true_ones(simulated):
    folder, out, report = simulated
    truth = _core.Skeleton.load(str(folder / "truth_skeleton.json"))
    estimated = _core.Skeleton.load(str(out / "skeleton.json"))
    limbs = [truth.bone_names.index(b) for b in ("shin_l", "shin_r", "foot_l", "foot_r", "forearm_l", "forearm_r",
                                                   "hand_l", "hand_r")]
    error = np.abs(np.linalg.norm(estimated.offsets, axis=1) - np.linalg.norm(truth.offsets, axis=1))[limbs]
    # Measured (seed 3): at most 1.2 cm (thigh), mean 0.8: the detector's 1-3 cm keypoint offsets
    # are not estimated, so the 1 cm is not reached everywhere.
    assert error.max() < 0.02 and error.mean() < 0.012, error.round(3)
    assert report["imus_used"] == 13


def imu_errors(folder, out) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per IMU (deg): heading, the bone axis' direction in the sensor frame (what video sees
    of the mounting), and the mounting in full, estimated (imus.json) against truth.json."""
    truth = json.loads((folder / "truth.json").read_text())
    skeleton = _core.Skeleton.load(str(folder / "truth_skeleton.json"))
    headings, axes, mounts = [], [], []
    for s in json.loads((out / "imus.json").read_text())["imus"]:
        true = truth["sensors"][s["name"]]
        ref = rotations.exp(np.array(s["reference"]))
        headings.append(abs((np.degrees(np.arctan2(ref[1, 0], ref[0, 0])) - true["heading_deg"] + 180) % 360 - 180))
        bone = skeleton.bone_names.index(s["bone"])
        child = [c for c, p in enumerate(skeleton.parents) if p == bone and np.linalg.norm(skeleton.offsets[c]) > 0]
        axis = skeleton.offsets[child[0]] / np.linalg.norm(skeleton.offsets[child[0]]) if child else np.array([0, 0, 1.0])
        est, want = rotations.exp(np.array(s["mount"])), rotations.exp(np.array(true["mount"]))
        axes.append(np.degrees(np.arccos(np.clip((est.T @ axis) @ (want.T @ axis), -1, 1))))
        mounts.append(np.degrees(rotations.angle_between(est, want)))
    return np.array(headings), np.array(axes), np.array(mounts)


def test_imu_headings_and_observed_mountings_are_recovered(simulated):
    headings, axes, _ = imu_errors(*simulated[:2])
    # Measured (seed 3): headings median 1.5 deg, up to 6.3, and 14.5 at the standing foot (it
    # barely turns in the window, and barely accelerates: without the accelerometer's headings
    # 27.6, and median 1.7); the bone axis in the sensor frame median 3.6 deg. The video-only
    # start (mocap.calibration.imus) was 7-30 deg.
    assert np.median(headings) < 2.5 and sorted(headings)[-2] < 8.0 and headings.max() < 20.0, np.round(headings, 1)
    assert np.median(axes) < 8.0, np.round(axes, 1)


def test_the_imus_make_the_joint_centres_steadier_and_no_worse_than_video_alone(simulated, video_only):
    fused = joint_centre_errors(*simulated[:2])
    video = joint_centre_errors(*video_only[:2])
    assert video_only[2]["imus_used"] == 0
    # Measured (4 s, seed 3): fused 1.99 cm, video only 1.86 cm (its skeleton from the same
    # window calibration; 2.31 cm before its frames' keypoints got the wider loss,
    # video_only_position_loss_scale, which the fused solve's frames do not have: a lead for
    # the fused solve, not yet tuned); frame-to-frame change of the error 1.8 times smaller
    # with the IMUs (1.6 against 2.8 mm).
    jitter = lambda e: np.abs(np.diff(e, axis=0)).mean()  # noqa: E731
    assert fused.mean() < 0.025 and fused.mean() < 1.15 * video.mean(), (fused.mean(), video.mean())
    assert jitter(fused) < 0.7 * jitter(video), (jitter(fused), jitter(video))


def test_a_held_t_pose_pins_the_mountings(simulated, tmp_path):
    """`mocap simulate --calibration-pose T`: the same 4 s after 1 s of a T-pose; the take
    solve finds the pose from the video and ties those frames to it."""
    folder = tmp_path / "take"
    subprocess.run([sys.executable, "-m", "mocap.cli", "simulate", "--take-out", str(folder), "--seconds", "4",
                    "--seed", "3", "--calibration-pose", "T"], check=True, capture_output=True)
    report = take_solve.solve_take(folder, tmp_path / "out")
    assert report["window"]["calibration_pose"] == "T"
    change = report["solve"]["heading_change_deg"]  # the heading tracking's, at the take's end
    assert len(change) == 13 and all(np.isfinite(v) and abs(v) < 20 for v in change.values()), change
    _, _, mounts = imu_errors(folder, tmp_path / "out")
    _, _, mounts_without = imu_errors(*simulated[:2])
    # Measured (seed 3): mountings in full median 3.6 deg with the pose, 14.7 without (their
    # twist is the prior's there); joint centres 1.38 cm, 1.99 without.
    assert np.median(mounts) < 6.0 and np.median(mounts) < 0.5 * np.median(mounts_without), mounts.round(1)
    assert joint_centre_errors(folder, tmp_path / "out").mean() < 0.9 * joint_centre_errors(*simulated[:2]).mean()


def test_a_still_start_is_passed_over(tmp_path):
    """`mocap simulate --still-start 5`: the performer stands still for 5 s, then moves. The
    first 5 s cannot tell the IMUs' headings from their mountings; the calibration waits for
    motion (mocap.calibration.informative) instead."""
    folder = tmp_path / "take"
    subprocess.run([sys.executable, "-m", "mocap.cli", "simulate", "--take-out", str(folder), "--seconds", "8",
                    "--seed", "3", "--still-start", "5"], check=True, capture_output=True)
    report = take_solve.solve_take(folder, tmp_path / "out")
    headings, _, _ = imu_errors(folder, tmp_path / "out")
    centres = joint_centre_errors(folder, tmp_path / "out")
    # Measured (seed 3): the window from 3.0 s (IMUs tilting 19.1 deg RMS); headings median
    # 0.7 deg, joint centres 2.07 cm. Calibrated from the first 5 s instead: headings median
    # 124 deg, joint centres 6.9 cm (9.8 after 6 s).
    assert report["window"]["window_start_s"] >= 2.0 and report["imus_used"] == 13, report["window"]["window_start_s"]
    assert np.median(headings) < 3.0 and centres.mean() < 0.025, (np.round(headings, 1), centres.mean())


@pytest.mark.skipif(not (TRIAL_CACHE / TRIAL_DONE).is_file(), reason="the real trial is not in .cache/")
def test_pose2sims_balancing_trial_as_a_take_lands_near_its_own_3d(tmp_path):
    """`mocap eval-edge --take-solve`, with and without the motion term E_M."""
    result = balancing_take.evaluate(TRIAL_CACHE, tmp_path / "with")
    without = balancing_take.evaluate(TRIAL_CACHE, tmp_path / "without", ["motion.enabled=false"])
    assert result["statuses"].get("ok", 0) == 99 and without["settings"] == ["motion.enabled=false"]
    # Measured (docs/results_real.md): 2.88 cm, jitter 13.9 m/s^2; without E_M 2.88 cm, 36.8.
    # The bounds are the targets (the solve is deterministic).
    assert result["distance_cm"] < 3.5 and result["jitter_ours_ms2"] < 15.0, result
    assert without["jitter_ours_ms2"] > 2.5 * result["jitter_ours_ms2"], (without, result)
    assert result["distance_cm"] < without["distance_cm"] + 0.1, (without, result)
    # Exported as TRC, the joint centres are Pose2Sim's markers, in its axes and units.
    trc = tmp_path / "with.trc"
    subprocess.run([sys.executable, "-m", "mocap.cli", "export", str(tmp_path / "with" / "solved"), "--format", "trc",
                    "--out", str(trc)], check=True, capture_output=True)
    ours, theirs = read_trc(trc), read_trc(TRIAL_CACHE / TRIAL)
    d = np.linalg.norm(ours.markers - theirs.markers[:, [theirs.names.index(n) for n in ours.names]], axis=-1)
    assert ours.rate == theirs.rate and abs(100 * d.mean() - result["distance_cm"]) < 1e-3, (d.mean(), result)


def test_a_take_seen_by_one_camera_cannot_be_calibrated(simulated, tmp_path):
    from mocap.calibration import from_messages
    from mocap.errors import InputError
    from mocap.io import take_folder
    from mocap.io.take_folder import read_take
    from mocap.takes import messages

    take = read_take(simulated[0])
    take.people = [take.people[0]] + [[np.zeros((0, take_folder.KEYPOINTS[take.layout], 3))] * take.n_frames for _ in take.people[1:]]
    session = messages.write_session(take, tmp_path / "session")
    with pytest.raises(InputError, match="two cameras"):
        from_messages.estimate(messages.messages(take), session, 5.0, "take")


def test_solve_wants_exactly_one_input(tmp_path):
    for args in ([], ["--recording", "x.mcap", "--take", str(tmp_path)]):
        out = subprocess.run([sys.executable, "-m", "mocap.cli", "solve", *args, "--out", str(tmp_path / "o")],
                             capture_output=True, text=True)
        assert out.returncode != 0 and "exactly one" in out.stderr and "Traceback" not in out.stderr
    out = subprocess.run([sys.executable, "-m", "mocap.cli", "solve", "--recording", "x.mcap", "--set",
                          "motion.enabled=false", "--out", str(tmp_path / "o")], capture_output=True, text=True)
    assert out.returncode != 0 and "--set is for --take" in out.stderr and "Traceback" not in out.stderr
    out = subprocess.run([sys.executable, "-m", "mocap.cli", "solve", "--take", str(tmp_path / "none"), "--out",
                          str(tmp_path / "o")], capture_output=True, text=True)
    assert out.returncode != 0 and "Traceback" not in out.stderr


def test_the_report_names_the_sensors_the_solve_left_out(simulated):
    report = simulated[2]
    assert report["solve"]["distrusted"] == {}, "the keypoints contradicted a true sensor"
    assert "left out of the solve" not in take_report.markdown(report)
    left_out = {**report, "solve": {**report["solve"], "distrusted": {"shin_r": {"first_s": 4.27, "seconds": 4.02}}}}
    assert "| shin_r | 4.27 | 4.02 |" in take_report.markdown(left_out)
