"""The demo motion: TRC reading, the cached download, the skeleton fit of the Pose2Sim
trial, the ping-pong loop and its simulated take."""

import dataclasses
import shutil
import subprocess

import numpy as np
import pytest

from mocap import _core, paths
from mocap.errors import DataMissingError, InputError
from mocap.io import demo_data, retarget
from mocap.io.trc import read_trc
from mocap.model import studio
from mocap.sim import demo_motion, take

HEADER = ("PathFileType\t4\t(X/Y/Z)\tsmall.trc\n"
          "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n"
          "50\t50\t3\t2\tmm\t50\t1\t3\n"
          "Frame#\tTime\tA\t\t\tB\t\t\n"
          "\t\tX1\tY1\tZ1\tX2\tY2\tZ2\n\n")
ROWS = ["1\t0.00\t1000\t2000\t3000\t10\t20\t30",
        "2\t0.02\t1100\tNaN\t3100\t\t\t",  # A's y and all of B missing
        "3\t0.04\t1200\t2200\t3200"]  # B missing at the end of the row


def write_trc(tmp_path, rows):
    path = tmp_path / "small.trc"
    path.write_text(HEADER + "\n".join(rows) + "\n")
    return path


def test_trc_is_read_in_metres_with_missing_markers_nan(tmp_path):
    trc = read_trc(write_trc(tmp_path, ROWS))
    assert trc.rate == 50 and trc.names == ["A", "B"]
    np.testing.assert_allclose(trc.times, [0, 0.02, 0.04])
    np.testing.assert_allclose(trc.markers[0], [[1, 2, 3], [0.01, 0.02, 0.03]])  # mm -> m
    np.testing.assert_allclose(trc.markers[2, 0], [1.2, 2.2, 3.2])
    assert np.isnan(trc.markers[1, 0, 1]) and not np.isnan(trc.markers[1, 0, [0, 2]]).any()
    assert np.isnan(trc.markers[1:, 1]).all()


@pytest.mark.parametrize("bad, message", [("2\t0.02\t1100\t2x00\t3100", r"small.trc:8, column 4: '2x00'"),
                                          ("2\t0.02" + "\t1" * 7, r"small.trc:8: 9 cells")])
def test_a_malformed_row_is_an_error_naming_its_line(tmp_path, bad, message):
    with pytest.raises(InputError, match=message):
        read_trc(write_trc(tmp_path, [ROWS[0], bad, ROWS[2]]))


def test_unknown_units_are_an_error(tmp_path):
    path = write_trc(tmp_path, ROWS)
    path.write_text(path.read_text().replace("\tmm\t", "\tfurlong\t"))
    with pytest.raises(InputError, match=r"small.trc:3"):
        read_trc(path)


@pytest.fixture(scope="module")
def cache():
    try:
        return demo_data.fetch()
    except DataMissingError as e:
        pytest.skip(f"the demo motion is not cached and cannot be fetched: {e}")


def test_fetch_uses_an_intact_cache_and_refuses_an_altered_one(cache, tmp_path, monkeypatch):
    def offline(*args, **kwargs):
        raise subprocess.CalledProcessError(1, args[0], stderr="no network")

    monkeypatch.setattr(subprocess, "run", offline)
    for name, _ in demo_data.MEMBERS.values():
        shutil.copy(cache / name, tmp_path / name)
    assert demo_data.fetch(tmp_path) == tmp_path  # no download attempted
    with open(tmp_path / demo_data.TRIAL, "a") as f:
        f.write("1\n")
    with pytest.raises(DataMissingError, match="no network"):
        demo_data.fetch(tmp_path)


@pytest.fixture(scope="module")
def trial(cache):
    trc = read_trc(cache / demo_data.TRIAL)
    world = demo_motion.world_markers(trc)
    skeleton, thetas, dt = demo_motion.fit_motion(trc, trc.rate)
    return trc, world, demo_motion.body_model(trc.names, world), skeleton, thetas, dt


def test_trial_is_read_as_described(trial):
    trc, world, *_ = trial
    assert trc.rate == 60 and trc.markers.shape == (100, 21, 3) and set(trc.names) == set(demo_motion.MARKERS)
    assert np.isfinite(trc.markers).all()


def test_world_is_z_up_right_handed(trial):
    trc, world, *_ = trial
    m = {n: world[:, k] for k, n in enumerate(trc.names)}
    np.testing.assert_allclose(world[..., :2], trc.markers[..., [2, 0]])  # file z, x -> world x, y
    height = world[..., 2] - trc.markers[..., 1]
    np.testing.assert_allclose(height, height[0, 0])  # file y, shifted
    assert (m["Head"][:, 2] > m["Neck"][:, 2]).all() and (m["Neck"][:, 2] > m["LHip"][:, 2]).all()
    facing = np.cross(m["LHip"] - m["RHip"], [0, 0, 1.0])  # left x up, in a right-handed world
    assert (np.sum((m["Nose"] - m["Neck"]) * facing, axis=1) > 0).mean() > 0.95


def test_skeleton_is_symmetric_with_the_markers_median_lengths(trial):
    trc, world, body, skeleton, *_ = trial
    np.testing.assert_array_equal(skeleton.offsets, body.skeleton.offsets)
    o, i = skeleton.offsets, retarget.BONES.index
    for bone in ("clavicle", "upper_arm", "forearm", "hand", "thigh", "shin", "foot", "toes"):
        np.testing.assert_allclose(o[i(bone + "_r")], o[i(bone + "_l")] * [1, -1, 1], atol=1e-12)
    m = {n: world[:, k] for k, n in enumerate(trc.names)}
    median = lambda a, b: np.median(np.linalg.norm(m[a] - m[b], axis=1))  # noqa: E731
    for bone, (a, b) in {"shin_l": ("Hip", "Knee"), "foot_l": ("Knee", "Ankle"), "forearm_l": ("Shoulder", "Elbow"),
                         "hand_l": ("Elbow", "Wrist")}.items():
        expected = (median("L" + a, "L" + b) + median("R" + a, "R" + b)) / 2
        assert np.linalg.norm(o[i(bone)]) == pytest.approx(expected, abs=1e-9), bone
    assert 2 * o[i("thigh_l"), 1] == pytest.approx(median("LHip", "RHip"))
    _, pos = skeleton.forward_kinematics(np.zeros(skeleton.pose_dim))
    shoulders = np.linalg.norm(pos[i("upper_arm_l")] - pos[i("upper_arm_r")])
    assert shoulders == pytest.approx(median("LShoulder", "RShoulder"))
    hips = (pos[i("thigh_l")] + pos[i("thigh_r")]) / 2
    assert np.linalg.norm(pos[i("neck")] - hips) == pytest.approx(np.median(
        np.linalg.norm(m["Neck"] - (m["LHip"] + m["RHip"]) / 2, axis=1)), abs=0.005)


# Measured: mean 12.6 mm, max 49 mm (a heel keypoint that jumps onto the ankle for a few
# frames); the keypoints' own distances vary by +-4 cm over the trial.
MEAN_RESIDUAL, MAX_RESIDUAL, MARKER_MEAN_RESIDUAL = 0.015, 0.06, 0.03  # m


def test_fitted_sites_follow_the_markers(trial):
    trc, world, body, _, thetas, _ = trial
    errors = demo_motion.marker_errors(body, world, thetas)
    assert errors.mean() < MEAN_RESIDUAL and errors.max() < MAX_RESIDUAL
    assert errors.mean(axis=0).max() < MARKER_MEAN_RESIDUAL


def test_missing_markers_are_left_out_of_the_fit(trial):
    trc, world, *_ = trial
    wrist = trc.names.index("LWrist")
    holey = trc.markers.copy()
    holey[30:45, wrist] = np.nan
    holey[50] = np.nan  # a frame without any marker keeps the pose
    holey_trc = dataclasses.replace(trc, markers=holey)
    _, thetas, _ = demo_motion.fit_motion(holey_trc, trc.rate)
    assert np.isfinite(thetas).all()
    body = demo_motion.body_model(trc.names, demo_motion.world_markers(holey_trc))
    errors = demo_motion.marker_errors(body, world, thetas)  # against the full markers
    assert np.delete(errors, wrist, axis=1).mean() < MEAN_RESIDUAL
    assert errors[30:45, wrist].max() < 0.08 and errors[50].max() < 0.05  # carried along, not lost


def test_subject_stands_on_the_floor(trial):
    trc, world, body, skeleton, thetas, _ = trial
    soles = [trc.names.index(s + n) for s in "LR" for n in ("Heel", "BigToe", "SmallToe")]
    lowest = np.array([studio.site_positions(skeleton, body.bones, body.offsets, t)[soles, 2].min() for t in thetas])
    assert abs(lowest[0]) < 0.02  # standing on both feet
    assert (lowest > -0.05).all() and (lowest < 0.03).all()  # always a foot on the floor, never deep in it


def joint_positions(skeleton, thetas):
    return np.array([skeleton.forward_kinematics(t)[1] for t in thetas])


def test_loop_turns_without_jump_or_jolt():
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    f = np.arange(60)[:, None]
    thetas = np.zeros((60, skeleton.pose_dim))
    thetas[:, 0] = 0.01 * f[:, 0]  # walks at 0.6 m/s
    thetas[:, 3 + 3 * skeleton.bone_index("upper_arm_l") + 2] = 0.02 * f[:, 0]  # swings an arm at 1.2 rad/s
    dt = 1 / 60
    loop = demo_motion.loop_motion(thetas, 10.0, dt)
    assert len(loop) == 600
    np.testing.assert_allclose(loop[0], thetas[0])
    turns = np.flatnonzero(np.diff(np.sign(np.diff(loop[:, 0]))) != 0)
    assert len(turns) >= 8
    assert np.isclose(loop[:, 0].max(), thetas[-1, 0]) and np.isclose(loop[:, 0].min(), thetas[0, 0])
    pos, original = joint_positions(skeleton, loop), joint_positions(skeleton, thetas)
    step = lambda p: np.linalg.norm(np.diff(p, axis=0), axis=-1).max()  # noqa: E731
    assert step(pos) <= step(original) + 1e-9
    accel = np.linalg.norm(np.diff(pos, 2, axis=0), axis=-1).max() / dt**2
    assert accel < 10.0  # m/s^2; a plain reversal at 0.6 m/s would be 72


def test_demo_motion_is_long_and_smooth(trial):
    _, _, _, _, thetas, _ = trial
    skeleton, loop, dt = demo_motion.load_motion(seconds=20.0)
    assert dt == pytest.approx(1 / 60) and len(loop) == 1200
    step = lambda p: np.linalg.norm(np.diff(p, axis=0), axis=-1).max(axis=1)  # noqa: E731
    assert step(joint_positions(skeleton, loop)).max() <= 1.001 * step(joint_positions(skeleton, thetas)).max()


def test_simulated_take_plays_the_motion(trial):
    *_, skeleton, thetas, dt = trial
    motion = thetas[:40]
    t = take.simulate_motion(skeleton, motion, dt, take.Config(), np.random.default_rng(0))
    np.testing.assert_array_equal(t.thetas, motion)
    np.testing.assert_array_equal(t.skeleton.offsets, skeleton.offsets)
    assert np.abs(t.times - np.arange(40) * dt).max() < 0.01
    assert t.quaternions.shape == (40, 13, 4) and len(t.keypoints) == 40
    seen = np.mean([(k[..., 2] > 0).mean() for k in t.keypoints])
    assert seen > 0.6  # the cameras are around the subject
