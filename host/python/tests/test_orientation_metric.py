"""The orientation error with each bone's constant offset removed (mocap.eval.metrics): it
ignores where a skeleton puts a bone's frame at rest, and keeps every error that changes
over the take."""

import numpy as np

from mocap import _core, paths, rotations
from mocap.eval import metrics


def _random_rotations(rng, shape, scale):
    return rotations.exp(rng.normal(scale=scale, size=(*shape, 3)))


def test_a_constant_offset_per_bone_is_no_error_and_tracking_error_stays():
    rng = np.random.default_rng(0)
    truth = _random_rotations(rng, (200, 5), 1.5)
    offsets = _random_rotations(rng, (5,), 1.0)  # up to ~100 deg: another rest-pose convention
    solved = truth @ np.swapaxes(offsets, -1, -2)[None]  # R_s = R_t D^T: R_t = R_s D
    assert np.degrees(rotations.angle_between(solved, truth)).mean() > 20
    assert np.allclose(metrics.offset_removed_errors_deg(solved, truth), 0.0, atol=1e-6)

    wobble = _random_rotations(rng, (200, 5), np.radians(3.0))  # 3 deg of tracking noise per axis
    noisy = solved @ wobble
    plain = np.degrees(rotations.angle_between(wobble, np.eye(3)))
    removed = metrics.offset_removed_errors_deg(noisy, truth)
    assert abs(removed.mean() - plain.mean()) < 0.5  # the noise is kept (the fitted offset absorbs its mean)
    assert removed.mean() > 4.0


def test_an_error_that_grows_over_the_take_is_not_taken_for_an_offset():
    rng = np.random.default_rng(1)
    truth = _random_rotations(rng, (100, 1), 1.0)
    drift = rotations.exp(np.linspace(0, np.radians(60), 100)[:, None, None] * np.array([0, 0, 1.0]))
    solved = truth @ drift
    removed = metrics.offset_removed_errors_deg(solved, truth)
    assert removed[0, 0] > 25 and removed[-1, 0] > 25  # the ends stay 30 deg from the mean offset


def test_a_bone_upside_down_all_take_is_counted_though_its_offset_removed_error_is_nil():
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    truth = np.zeros((30, skeleton.pose_dim))
    truth[:, 2] = 1.0
    truth[:, 3 + 3 * skeleton.bone_names.index("shin_l")] = 0.3
    solved = truth.copy()
    foot = skeleton.bone_names.index("foot_r")
    solved[:, 3 + 3 * foot: 6 + 3 * foot] = [np.pi * 0.97, 0, 0]  # rolled about its long axis
    e = metrics.errors(skeleton, truth, solved, 1 / 60)
    assert e["per_joint"]["foot_r"]["ori_offset_removed_deg"] < 1e-6
    assert e["upside_down_frames"]["foot_r"] == 30
    assert "foot_l" not in e["upside_down_frames"]
