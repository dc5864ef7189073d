import json

import numpy as np
import pytest

from mocap import paths
from mocap.model import prior


def test_kmeans_finds_separated_clusters_whatever_their_sizes():
    rng = np.random.default_rng(0)
    centres = np.array([[0.0, 0.0], [5.0, 5.0], [-5.0, 5.0]])
    x = np.concatenate([c + 0.1 * rng.normal(size=(n, 2)) for c, n in zip(centres, (1000, 20, 20))])
    found = prior.kmeans(x, 3, seed=1)
    for c in centres:
        assert np.linalg.norm(found - c, axis=1).min() < 0.1


def test_clustering_keeps_common_poses_from_dominating():
    rng = np.random.default_rng(1)
    poses = np.zeros((1040, 66))
    poses[:1000, 6:] = 0.01 * rng.normal(size=(1000, 60))  # "standing", over-represented
    poses[1000:1020, 6] = 1.0
    poses[1020:, 7] = 1.0
    plain = prior.fit(poses, clusters=None)
    clustered = prior.fit(poses, clusters=3)
    assert abs(plain.mean[0]) < 0.05  # the mean sits on the common pose
    assert clustered.mean[0] == pytest.approx(1 / 3, abs=0.02)  # each pose counts once


def test_keeps_the_requested_share_of_variance():
    rng = np.random.default_rng(2)
    scales = np.r_[np.full(5, 1.0), np.full(55, 0.01)]  # 5 strong directions
    poses = np.zeros((2000, 66))
    poses[:, 6:] = rng.normal(size=(2000, 60)) * scales @ np.linalg.qr(rng.normal(size=(60, 60)))[0]
    model = prior.fit(poses, variance=0.95, clusters=None)
    assert model.basis.shape == (60, 5)
    np.testing.assert_allclose(model.sigma, 1.0, rtol=0.1)


def test_shipped_prior_is_trained_on_the_train_split_and_reproducible(shared):
    shipped = json.loads(prior.DEFAULT.read_text())
    assert not set(shipped["training"]["clips"]) & prior.held_out_clips()
    assert prior.test_clips() and prior.validation_clips() and not prior.test_clips() & prior.validation_clips()
    retrained, info = prior.train(shared / "data/mocap", exclude=prior.held_out_clips())
    assert info["clips"] == shipped["training"]["clips"]
    np.testing.assert_allclose(retrained.mean, shipped["mean"], atol=1e-9)
    # Components are defined up to sign.
    for a, b in zip(retrained.basis.T, np.asarray(shipped["basis"])):
        assert abs(abs(a @ b) - 1.0) < 1e-6


def test_shipped_prior_loads():
    model = prior.load()
    assert model.basis.shape[0] == 60 and 10 <= model.basis.shape[1] <= 30
    assert paths.HOST_DATA in prior.DEFAULT.parents
