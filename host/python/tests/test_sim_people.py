"""Several performers on one simulated stage (mocap.sim.people): placed where the placement
says, hiding each other from the cameras they stand in front of, and listed by each camera in
an order that says nothing of who they are."""

import numpy as np
import pytest

from mocap import _core, paths, rotations
from mocap.model import studio
from mocap.sim import messages, occlusion, people
from mocap.sim.take import Config

CLIPS = ("cmu-131/131_01.bvh", "cmu-daz/07_03.bvh")  # test-split clips: a walk each


def _default_skeleton() -> _core.Skeleton:
    return _core.Skeleton.load(str(paths.DEFAULT_SKELETON))


def test_a_placed_motion_is_the_same_motion_turned_and_moved_on_the_floor():
    skeleton = _default_skeleton()
    rng = np.random.default_rng(1)
    thetas = np.zeros((5, 66))
    thetas[:, :3] = [[1.0 + 0.3 * f, 2.0, 0.95] for f in range(5)]
    thetas[:, 3:] = rng.normal(scale=0.3, size=(5, 63))
    placed = people.place(thetas, 90.0, (-0.5, 0.25))
    turn = rotations.exp(np.array([0.0, 0.0, np.pi / 2]))
    mean = np.array([thetas[:, 0].mean(), thetas[:, 1].mean(), 0.0])
    for before, after in zip(thetas, placed):
        _, joints = skeleton.forward_kinematics(before)
        _, moved = skeleton.forward_kinematics(after)
        assert np.allclose(moved, (joints - mean) @ turn.T + [-0.5, 0.25, 0.0], atol=1e-9)


def test_a_person_between_a_camera_and_another_hides_them_from_it_only():
    skeleton = _default_skeleton()
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / "blazepose33.json"), skeleton).scaled_to(skeleton)
    caps = occlusion.capsules(skeleton.bone_names, skeleton.parents)
    back, front = np.zeros(66), np.zeros(66)
    back[:3], front[:3] = [0.0, 0.0, 0.95], [0.0, -1.0, 0.95]
    rig = studio.ring_rig(4, radius=4.0, heights=(1.0, 1.0))  # at chest height, one behind the front person
    centres = np.array([c.center() for c in rig.cameras])
    behind = int(np.argmin(centres[:, 1]))
    points = studio.site_positions(skeleton, layout.bones, layout.offsets, back)
    alone = occlusion.hidden(centres, points, np.asarray(layout.bones), *skeleton.forward_kinematics(back), caps,
                             skeleton.parents)
    others = occlusion.segments(*skeleton.forward_kinematics(front), caps)
    crowded = occlusion.hidden(centres, points, np.asarray(layout.bones), *skeleton.forward_kinematics(back), caps,
                               skeleton.parents, others)
    assert crowded[behind].mean() > 0.8 > alone[behind].mean()  # the front person covers the back one
    facing = int(np.argmax(centres[:, 1]))  # the camera the back person stands in front of
    assert (crowded[facing] == alone[facing]).all()


def test_a_scene_lists_who_each_camera_finds_in_an_order_of_its_own(shared):
    clips = [shared / "data" / "mocap" / c for c in CLIPS]
    scene = people.simulate(clips, 3, 3.0, Config(), np.random.default_rng(0))
    assert len(scene.performers) == 3 and scene.placements[2].clip == 0 and scene.placements[2].start_s > 0
    frames = len(scene.persons)
    assert frames == len(scene.performers[0].thetas) and 150 <= frames <= 181
    means = np.array([t.thetas[:, :2].mean(axis=0) for t in scene.performers])
    spacing = np.linalg.norm(means[:, None] - means[None], axis=-1)[np.triu_indices(3, 1)]
    assert np.allclose(spacing, people.SPACING_M)
    shuffled = missing = 0
    for f in range(frames):
        for c, (dets, who) in enumerate(zip(scene.persons[f], scene.who[f])):
            assert sorted(who) == sorted(set(who)) and len(dets) == len(who)
            for det, p in zip(dets, who):  # each listed person is that performer's detection in the camera
                assert np.array_equal(det, scene.performers[p].keypoints[f][c])
            shuffled += who != sorted(who)
            missing += len(who) < 3
    assert shuffled > frames  # the cameras' order is not the performers'
    assert missing > 0  # someone is hidden from some camera at some time


def test_a_suit_sensors_name_says_whose_suit_it_is():
    assert [messages.suit_of_sensor(messages.suit_sensor(p, "foot_l")) for p in (0, 3, 12)] == [0, 3, 12]
    for bad in ("foot_l", "px_foot", "p_foot", ""):
        with pytest.raises(ValueError, match="not a suit's sensor"):
            messages.suit_of_sensor(bad)
