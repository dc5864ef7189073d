"""Joints bent beyond the clips and sensors slipping mid-take (mocap.sim.extremes): the truth
and the readings change as a bent joint and a turned sensor would change them."""

import dataclasses

import numpy as np
import pytest

from mocap import _core, paths, rotations
from mocap.errors import InputError
from mocap.sim import extremes
from mocap.sim import take as sim_take


@pytest.fixture(scope="module")
def skeleton():
    return _core.Skeleton.load(str(paths.DEFAULT_SKELETON))


def test_a_bend_turns_its_bones_about_their_own_axis_once_eased_in(skeleton):
    names = skeleton.bone_names
    rng = np.random.default_rng(0)
    thetas = rng.normal(scale=0.3, size=(121, 66))
    b = extremes.Bend(("foot_l", "hand_r"), "x", 80.0, from_s=0.5, ramp_s=0.5)
    bent = extremes.bend(thetas, names, b, dt=1 / 60)
    for name in b.bones:
        j = 3 + 3 * names.index(name)
        turn = rotations.exp(thetas[:, j:j + 3]).swapaxes(-1, -2) @ rotations.exp(bent[:, j:j + 3])
        angle = np.degrees(rotations.angle_between(np.eye(3), turn))
        assert np.allclose(angle[:30], 0, atol=1e-9)  # before from_s
        assert np.allclose(angle[60:], 80.0, atol=1e-6)  # eased in by from_s + ramp_s
        assert np.allclose(rotations.log(turn[60:]) / np.radians(80.0), [1, 0, 0], atol=1e-6)  # about the bone's x
    others = [k for k in range(66) if not any(3 + 3 * names.index(n) <= k < 6 + 3 * names.index(n) for n in b.bones)]
    assert np.array_equal(bent[:, others], thetas[:, others])


def test_a_slipped_sensor_reads_its_turned_frame_from_the_slip_on():
    rng = np.random.default_rng(1)
    q = rotations.quaternion_from_matrix(rotations.exp(rng.normal(size=(50, 2, 3))))
    a = rng.normal(size=(50, 2, 3))
    times = np.arange(50) * 0.1
    s = extremes.Slip("b", at_s=2.0, axis="z", degrees=60.0)
    q2, a2 = extremes.slip(q, a, ["a", "b"], times, s)
    assert np.array_equal(q2[:, 0], q[:, 0]) and np.array_equal(a2[:20], a[:20]) and np.array_equal(q2[:20], q[:20])
    turn = rotations.exp(np.radians([0, 0, 60.0]))
    r, r2 = rotations.matrix_from_quaternion(q[20:, 1]), rotations.matrix_from_quaternion(q2[20:, 1])
    assert np.allclose(r2, r @ turn, atol=1e-12)
    # the same world acceleration, seen in the turned frame
    assert np.allclose(np.einsum("fij,fj->fi", r2, a2[20:, 1]), np.einsum("fij,fj->fi", r, a[20:, 1]), atol=1e-12)


def test_a_simulated_take_carries_the_bend_in_its_truth_and_the_slip_in_its_readings(skeleton):
    thetas = np.zeros((90, 66))
    thetas[:, 2] = 1.0
    bent = sim_take.Config(preset="hq6", bends=(extremes.Bend(("shin_l",), "x", 45.0, 0.2, 0.2),))
    config = dataclasses.replace(bent, slips=(extremes.Slip("forearm_l", 1.0, "y", 30.0),))
    plain = sim_take.simulate_motion(skeleton, thetas, 1 / 60, bent, np.random.default_rng(2))
    t = sim_take.simulate_motion(skeleton, thetas, 1 / 60, config, np.random.default_rng(2))
    j = 3 + 3 * skeleton.bone_names.index("shin_l")
    assert np.degrees(np.linalg.norm(t.thetas[-1, j:j + 3])) == pytest.approx(45.0)
    i = [s.name for s in t.imus].index("forearm_l")
    before, after = slice(0, 55), slice(65, 90)
    assert np.allclose(t.quaternions[before, i], plain.quaternions[before, i])
    turned = np.degrees(rotations.angle_between(rotations.matrix_from_quaternion(t.quaternions[after, i]),
                                                rotations.matrix_from_quaternion(plain.quaternions[after, i])))
    assert np.allclose(turned, 30.0, atol=1e-6)


@pytest.mark.parametrize("text", ["foot_l:w:90", "foot_l:x", "foot_l:x:ninety"])
def test_a_malformed_bend_says_how_to_write_it(text):
    with pytest.raises(InputError, match="BONE"):
        extremes.Bend.parse(text)


def test_a_slip_of_an_unknown_sensor_names_the_known_ones():
    with pytest.raises(InputError, match="no sensor 'ankle_x'.*forearm_l"):
        extremes.slip(np.zeros((2, 1, 4)), np.zeros((2, 1, 3)), ["forearm_l"], np.zeros(2),
                      extremes.Slip.parse("ankle_x:1:z:30"))
