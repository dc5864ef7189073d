import numpy as np

from mocap import _core, rotations


def test_round_trips_and_agreement_with_the_cpp_code():
    rng = np.random.default_rng(0)
    w = rng.normal(size=(500, 3)) * 1.5
    w[0] = [0, 0, np.pi - 1e-9]  # near pi, where naive formulas break
    w[1] = [1e-12, 0, 0]
    r = rotations.exp(w)
    np.testing.assert_allclose(rotations.matrix_from_quaternion(rotations.quaternion_from_matrix(r)), r, atol=1e-12)
    np.testing.assert_allclose(rotations.exp(rotations.log(r)), r, atol=1e-9)
    for i in range(5):
        np.testing.assert_allclose(_core.so3_exp(w[i]), r[i], atol=1e-12)
    np.testing.assert_allclose(rotations.angle_between(r[2], r[2] @ rotations.exp(np.array([0, 0.3, 0]))), 0.3)
