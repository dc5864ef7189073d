"""The simulated studio's error models do what their documentation says."""

import dataclasses

import numpy as np
import pytest

from mocap import _core, paths, rotations
from mocap.sim import detector, imu, occlusion


def test_mirror_pairs_left_and_right_in_every_layout_naming():
    assert list(detector.mirror(["nose", "left_eye", "right_eye"])) == [0, 2, 1]
    assert list(detector.mirror(["Nose", "LEye", "REye", "LBigToe", "RBigToe"])) == [0, 2, 1, 4, 3]
    assert list(detector.mirror(["mouth_left", "mouth_right"])) == [1, 0]


def test_random_errors_have_the_documented_size_and_rates():
    rng = np.random.default_rng(0)
    k, frames = 33, 3000
    pixels = np.column_stack([np.linspace(800, 1100, k), np.linspace(200, 900, k)])  # 700 px tall
    twins = np.arange(k)[::-1]
    errors = detector.DetectorErrors()
    err, swapped, conf = [], 0, []
    for _ in range(frames):
        det = detector.detect(pixels, np.ones(k, bool), twins, (1920, 1080), errors, rng)
        e = np.linalg.norm(det[:, :2] - pixels, axis=1)
        swapped += np.median(e) > 100
        if np.median(e) < 100:
            err.append(e)
            conf.append(det[:, 2])
    err, conf = np.concatenate(err), np.concatenate(conf)
    sigma = 0.01 * 700
    inliers = err < 10 * sigma
    assert np.sqrt(np.mean(err[inliers] ** 2) / 2) == pytest.approx(sigma, rel=0.15)  # per axis
    assert (~inliers).mean() == pytest.approx(0.03, abs=0.01)  # gross outliers
    assert swapped / frames == pytest.approx(0.02, abs=0.01)
    assert conf[~inliers].mean() < 0.3 < 0.8 < conf[inliers].mean()  # confidence falls with error


def test_systematic_only_and_offsets():
    rng = np.random.default_rng(1)
    off = detector.site_offsets(1000, detector.DetectorErrors(), rng)
    assert 0.01 <= np.linalg.norm(off, axis=1).min() and np.linalg.norm(off, axis=1).max() <= 0.03
    assert not detector.site_offsets(5, detector.DetectorErrors(site_offsets=False), rng).any()
    pixels = np.array([[100.0, 100.0], [200.0, 300.0]])
    det = detector.detect(pixels, np.array([True, False]), np.array([0, 1]), (640, 480),
                          detector.DetectorErrors(random=False), rng)
    np.testing.assert_allclose(det[0, :2], pixels[0])
    assert det[1, 2] == 0  # not visible: no detection


def test_a_hand_behind_the_back_is_hidden_from_a_camera_in_front():
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    theta = np.zeros(skeleton.pose_dim)
    theta[2] = 0.95
    rot, pos = skeleton.forward_kinematics(theta)
    caps = occlusion.capsules(skeleton.bone_names, skeleton.parents)
    chest = skeleton.bone_index("spine_upper")
    behind = pos[chest] + np.array([-0.3, 0.0, 0.0])  # 30 cm behind the chest
    points = np.array([behind, pos[chest] + [0.3, 0.0, 0.0]])
    bones = np.array([skeleton.bone_index("hand_l"), skeleton.bone_index("hand_l")])
    cameras = np.array([[4.0, 0.0, pos[chest][2]], [-4.0, 0.0, pos[chest][2]]])  # front, back
    hidden = occlusion.hidden(cameras, points, bones, rot, pos, caps, skeleton.parents)
    assert hidden.tolist() == [[True, False], [False, True]]


def test_imu_errors_match_the_spec():
    rng = np.random.default_rng(2)
    f, m = 4000, 20
    truth = np.broadcast_to(np.eye(3), (f, m, 3, 3)).copy()
    times = np.arange(f) / 60.0
    errors = dataclasses.replace(imu.ImuErrors(), heading_drift_deg_per_sqrt_min=0.0, wobble_deg_per_ms2=0.0)
    measured, accel = imu.corrupt(truth, np.zeros((f, m, 3)), np.tile([0, 0, 1.0], (f, m, 1)), times, errors, rng)
    w = np.degrees(rotations.log(measured))
    assert np.sqrt((w[..., 0] ** 2).mean()) == pytest.approx(0.75, rel=0.1)
    assert np.sqrt((w[..., 2] ** 2).mean()) == pytest.approx(1.5, rel=0.1)
    # Slow, as a filtered orientation is: a frame differs from the last by a fraction of that.
    step = np.degrees(rotations.angle_between(measured[1:], measured[:-1]))
    assert 0.02 < np.median(step) < 0.3
    assert accel[..., 2].mean() == pytest.approx(9.80665, abs=0.2)  # gravity's reaction, + bias
    assert (accel - accel.mean(axis=0)).std() == pytest.approx(0.03, rel=0.1)


def test_eval_scores_a_short_take(shared, tmp_path):
    import json

    from mocap import cli

    out = tmp_path / "eval.json"
    assert cli.main(["eval", "--motion", str(shared / "data/mocap/cmu-daz/16_36.bvh"), "--preset", "hq13",
                     "--calibration", "oracle", "--json", str(out)]) == 0
    result = json.loads(out.read_text())
    assert result["calibration"] == "oracle" and result["frames"] > 50
    assert 1.0 < result["floor_cm"] < 3.5  # 1-3 cm site offsets + camera perturbation
    assert result["pos_error_cm"] < 2 * result["floor_cm"]
    assert result["ori_error_deg"] < 30


def test_eval_estimates_the_calibration_by_default(shared, tmp_path):
    import json

    from mocap import cli

    clip = str(shared / "data/mocap/cmu-daz/16_31.bvh")
    results = {}
    for calibration in ("estimated", "oracle"):
        out = tmp_path / f"{calibration}.json"
        args = ["eval", "--motion", clip, "--json", str(out)] + (["--calibration", "oracle"] if calibration == "oracle" else [])
        assert cli.main(args) == 0
        results[calibration] = json.loads(out.read_text())["clips"][0]
    est, oracle = results["estimated"], results["oracle"]
    assert est["calibration"] == "estimated" and est["calibration_report"]["frames"] > 50
    # Measured: joint centres 1.83 (estimated) vs 1.40 cm (oracle), velocity 15.2 vs 14.9 cm/s;
    # the headings and the limb lengths come back to a few degrees and centimetres.
    assert est["joint_centres_pos_cm"] < 1.5 * oracle["joint_centres_pos_cm"]
    assert est["joint_centres_vel_cms"] < 1.2 * oracle["joint_centres_vel_cms"]
    errors = est["calibration_errors"]
    assert np.median([i["heading_deg"] for i in errors["imus"].values()]) < 5.0
    assert max(abs(v) for v in errors["limb_length_cm"].values()) < 3.0


def test_imu_stats_of_the_real_recordings(shared):
    from mocap.sim import imu_stats

    stats = imu_stats.stats(shared / "data/imu")
    noise = np.array(stats["handheld"]["accel_noise_ms2"] +
                     [v for s in stats["xsens_mtw_walking"].values() for v in s["accel_noise_ms2"]])
    assert len(stats["xsens_mtw_walking"]) == 8 and stats["handheld"]["stationary_blocks"] >= 3
    # The simulator's 0.03 m/s^2 white noise sits inside what the sensors show at rest.
    assert noise.min() < imu.ImuErrors().accel_noise < noise.max() < 0.1
    assert abs(stats["handheld"]["accel_norm_bias_ms2"]) < 2 * imu.ImuErrors().accel_bias
    # At rest the MTw orientation moves by hundredths of a degree per sample: the
    # simulator's per-sample white noise is of that order, not of the spec's RMS.
    steps = [s["orientation_step_deg"] for s in stats["xsens_mtw_walking"].values()]
    assert max(steps) < 0.1 and imu.ImuErrors().white_deg < 2 * max(steps)


def test_imu_only_baseline_follows_the_sensors(shared):
    from mocap.eval import baselines, metrics
    from mocap.sim import take

    config = take.Config(preset="hq13", imu=dataclasses.replace(imu.ImuErrors(), random=False))
    t = take.simulate(shared / "data/mocap/cmu-daz/16_36.bvh", config, np.random.default_rng(0))
    result = metrics.errors(t.skeleton, t.thetas, baselines.imu_only(t), 1 / 60)
    # Noise-free sensors: every bone carrying one is exact, and the root is aligned.
    for name in ("pelvis", "spine_upper", "forearm_l", "shin_r", "foot_l"):
        assert result["per_joint"][name]["ori_deg"] < 1e-6
    assert result["per_joint"]["pelvis"]["pos_cm"] < 1e-9


def test_camera_positions_spread_round_the_ring():
    from mocap.sim.take import camera_positions

    assert camera_positions(8) == list(range(8))
    assert camera_positions(4) == [0, 2, 4, 6]
    assert camera_positions(2) == [0, 2]  # 90 degrees apart, never opposite
    with pytest.raises(ValueError):
        camera_positions(9)


def test_a_stage_of_dozens_of_cameras_rings_the_performer_and_every_camera_sees_them():
    from mocap.sim.take import camera_rig

    thetas = np.zeros((2, 66))
    thetas[:, :3] = [1.0, -2.0, 1.0]
    rig = camera_rig(32, thetas)
    centres = np.array([c.center() for c in rig.cameras])
    assert len(rig.cameras) == 32 and len({c.name for c in rig.cameras}) == 32
    around = centres[:, :2] - [1.0, -2.0]
    assert np.allclose(np.linalg.norm(around, axis=1), 4.5)  # on a ring round the motion
    angles = np.sort(np.degrees(np.arctan2(around[:, 1], around[:, 0])) % 360)
    assert np.allclose(np.diff(angles), 360 / 32)  # evenly
    assert sorted(set(np.round(centres[:, 2], 6))) == [1.0, 2.5]  # low and high
    for c in rig.cameras:  # the performer is in every image
        pixels, valid = c.project(np.array([[1.0, -2.0, 1.0]]))
        assert valid[0] and np.allclose(pixels[0], [c.width / 2, c.height / 2], atol=1.0)
    eight = camera_rig(8, thetas)  # up to 8: the ring's positions as before
    assert [c.name for c in camera_rig(4, thetas).cameras] == [eight.cameras[i].name for i in (0, 2, 4, 6)]
