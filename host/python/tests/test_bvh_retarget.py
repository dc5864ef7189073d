"""BVH parsing, joint correspondence and the pose vectors it produces."""

import numpy as np
import pytest

from mocap import _core, rotations
from mocap.errors import InputError
from mocap.io import bvh
from mocap.io import retarget

# A small MotionBuilder-style clip: y up, left +x, facing +z, centimetres.
CLIP = """HIERARCHY
ROOT Hips
{
 OFFSET 0 0 0
 CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
 JOINT Spine { OFFSET 0 10 0 CHANNELS 3 Zrotation Xrotation Yrotation
  JOINT Spine1 { OFFSET 0 20 0 CHANNELS 3 Zrotation Xrotation Yrotation
   JOINT Neck { OFFSET 0 22 0 CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT Head { OFFSET 0 10 0 CHANNELS 3 Zrotation Xrotation Yrotation End Site { OFFSET 0 18 0 } } }
   JOINT LeftShoulder { OFFSET 2 17 0 CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftArm { OFFSET 16 0 0 CHANNELS 3 Zrotation Xrotation Yrotation
     JOINT LeftForeArm { OFFSET 28 0 0 CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT LeftHand { OFFSET 26 0 0 CHANNELS 3 Zrotation Xrotation Yrotation End Site { OFFSET 10 0 0 } } } } }
   JOINT RightShoulder { OFFSET -2 17 0 CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT RightArm { OFFSET -16 0 0 CHANNELS 3 Zrotation Xrotation Yrotation
     JOINT RightForeArm { OFFSET -28 0 0 CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT RightHand { OFFSET -26 0 0 CHANNELS 3 Zrotation Xrotation Yrotation End Site { OFFSET -10 0 0 } } } } } } }
 JOINT LeftUpLeg { OFFSET 9 -2 0 CHANNELS 3 Zrotation Xrotation Yrotation
  JOINT LeftLeg { OFFSET 0 -42 0 CHANNELS 3 Zrotation Xrotation Yrotation
   JOINT LeftFoot { OFFSET 0 -41 0 CHANNELS 3 Zrotation Xrotation Yrotation End Site { OFFSET 0 -6 14 } } } }
 JOINT RightUpLeg { OFFSET -9 -2 0 CHANNELS 3 Zrotation Xrotation Yrotation
  JOINT RightLeg { OFFSET 0 -42 0 CHANNELS 3 Zrotation Xrotation Yrotation
   JOINT RightFoot { OFFSET 0 -41 0 CHANNELS 3 Zrotation Xrotation Yrotation End Site { OFFSET 0 -6 14 } } } }
}
MOTION
Frames: 2
Frame Time: 0.0083333
"""
WIDTH = 6 + 3 * 18


def clip(frames: np.ndarray) -> bvh.Motion:
    body = "\n".join(" ".join(f"{v:.6f}" for v in row) for row in frames)
    return bvh.parse(CLIP + body + "\n")


def test_channels_are_applied_in_the_file_order():
    frames = np.zeros((2, WIDTH))
    frames[1, 3:6] = [90.0, 90.0, 0.0]  # Zrotation 90 then Xrotation 90: R = Rz Rx
    rot, _ = clip(frames).global_transforms()
    rz = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    rx = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0.0]])
    np.testing.assert_allclose(rot[1, 0], rz @ rx, atol=1e-12)


def test_correspondence_units_and_axes():
    motion = clip(np.zeros((2, WIDTH)))
    mapping = retarget.map_joints(motion)
    assert mapping.scale == 0.01  # centimetres
    names = [motion.joints[j].name if j is not None else None for j in mapping.joint]
    assert names[retarget.BONES.index("clavicle_l")] == "LeftShoulder"
    assert names[retarget.BONES.index("upper_arm_l")] == "LeftArm"
    assert names[retarget.BONES.index("toes_l")] is None  # sits at the foot's End Site
    # BVH left (+x) becomes solver left (+y); BVH forward (+z) becomes solver +x. This
    # clip's legs are straight as the canonical rest pose's, so their offsets are kept.
    np.testing.assert_allclose(mapping.offsets[retarget.BONES.index("shin_l")], [0, 0, -0.42], atol=1e-12)
    np.testing.assert_allclose(mapping.offsets[retarget.BONES.index("toes_l")], [0.14, 0, -0.06], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(mapping.offsets[retarget.BONES.index("thigh_l")]), np.hypot(0.09, 0.02))


def test_poses_reproduce_the_clips_joint_positions():
    rng = np.random.default_rng(0)
    frames = rng.uniform(-40, 40, size=(2, WIDTH))
    frames[:, 0:3] = [[10, 95, -20], [12, 94, -18]]
    motion = clip(frames)
    mapping = retarget.map_joints(motion)
    skeleton = _core.Skeleton.from_bones(retarget.BONES, mapping.parents, mapping.offsets)
    thetas = retarget.poses(motion, mapping)
    rot, pos = motion.global_transforms()
    for f in range(2):
        r_solver, p_solver = skeleton.forward_kinematics(thetas[f])
        for b, j in enumerate(mapping.joint):
            if j is None:
                continue
            np.testing.assert_allclose(p_solver[b], retarget.P @ pos[f, j] * 0.01, atol=1e-9)
            expected = retarget.P @ rot[f, j] @ retarget.P.T @ mapping.corrections[b]
            np.testing.assert_allclose(r_solver[b], expected, atol=1e-9)


def test_rest_poses_are_re_expressed_against_the_canonical_t_pose():
    # The same hierarchy with arms hanging 45 degrees down (an A-pose rest): at zero
    # channels the upper arm's world orientation must be the canonical one (arm along +y)
    # turned 45 degrees down; the T-pose rest leaves it as it is.
    a_pose = CLIP.replace("OFFSET 28 0 0", "OFFSET 19.79899 -19.79899 0").replace(
        "OFFSET 26 0 0", "OFFSET 18.38478 -18.38478 0").replace("OFFSET 10 0 0", "OFFSET 7.07107 -7.07107 0")
    arm = retarget.BONES.index("upper_arm_l")
    for text, expected_deg in ((CLIP, 0.0), (a_pose, 45.0)):
        motion = bvh.parse(text + "\n".join(" ".join(["0"] * WIDTH) for _ in range(2)) + "\n")
        mapping = retarget.map_joints(motion)
        skeleton = _core.Skeleton.from_bones(retarget.BONES, mapping.parents, mapping.offsets)
        rot, _ = skeleton.forward_kinematics(retarget.poses(motion, mapping)[0])
        w = rotations.log(rot[arm])
        assert np.degrees(np.linalg.norm(w)) == pytest.approx(expected_deg, abs=1e-6)
        if expected_deg:
            # +y turned down towards -z: a rotation about -x
            np.testing.assert_allclose(w / np.linalg.norm(w), [-1.0, 0.0, 0.0], atol=1e-9)


def test_malformed_files_raise_input_errors():
    with pytest.raises(InputError, match="HIERARCHY"):
        bvh.parse("MOTION")
    with pytest.raises(InputError, match="frames present"):
        bvh.parse(CLIP + "0 0 0\n")
    motion = clip(np.zeros((2, WIDTH)))
    motion.joints[motion.index("Head")].name = "Skull"
    with pytest.raises(InputError, match="head"):
        retarget.map_joints(motion)


def test_any_bytes_are_a_clip_or_an_input_error(tmp_path):
    """Inputs the fuzzer found (tests/fuzz/fuzz_bvh.py) and the caps they led to: bytes that are
    not UTF-8, counts that are not whole numbers, unknown channels, non-finite offsets, a frame
    count beyond the file's values (a clip without channels once allocated any count declared)."""
    path = tmp_path / "clip.bvh"
    path.write_bytes(CLIP.encode() + b"\xc6\x00")
    with pytest.raises(InputError, match="cannot read"):
        bvh.load(path)
    zeros = "\n".join(" ".join(["0"] * WIDTH) for _ in range(2))
    for text, what in ((CLIP.replace("CHANNELS 6", "CHANNELS six", 1), "not a whole number"),
                       (CLIP.replace("CHANNELS 6", "CHANNELS 7", 1), "not a whole number 0..6"),
                       (CLIP.replace("Zrotation", "Wrotation", 1), "are not"),
                       (CLIP.replace("OFFSET 0 10 0", "OFFSET 0 nan 0", 1), "finite"),
                       (CLIP.replace("Frames: 2", "Frames: -2"), "not a whole number"),
                       (CLIP.replace("Frames: 2", "Frames: 99999999999"), "not a whole number"),
                       (CLIP.replace("Frame Time: 0.0083333", "Frame Time: x"), "numbers"),
                       ("HIERARCHY ROOT a { OFFSET 0 0 0 } MOTION Frames: 0 Frame Time: 1", "frames present")):
        with pytest.raises(InputError, match=what):
            bvh.parse(text + zeros)


def test_real_clips_of_every_convention_map(shared):
    for relative in ("data/mocap/cmu-131/131_01.bvh", "data/mocap/cmu-daz/05_01.bvh", "data/mocap/xia/neutral_01_000.bvh"):
        motion = bvh.load(shared / relative)
        mapping = retarget.map_joints(motion)
        skeleton = _core.Skeleton.from_bones(retarget.BONES, mapping.parents, mapping.offsets)
        assert 1.1 < skeleton.rest_height() < 1.8, relative
        thetas = retarget.poses(motion, mapping)
        assert np.isfinite(thetas).all()
        # Upright after the axis change: the head is well above the pelvis mid-clip.
        _, pos = skeleton.forward_kinematics(thetas[len(thetas) // 2])
        assert pos[retarget.BONES.index("head")][2] > pos[0][2] + 0.3, relative


def test_smoothing_removes_jitter_not_motion():
    rng = np.random.default_rng(4)
    f = 600
    t = np.arange(f) / 120.0
    clean = np.zeros((f, 66))
    clean[:, 0] = 1.2 * t  # walking forward
    clean[:, 3:6] = np.c_[np.zeros(f), np.zeros(f), 0.9 * t]  # the root turns past pi: sign flips
    clean[:, 9:12] = np.c_[0.5 * np.sin(2 * np.pi * 1.0 * t), np.zeros(f), np.zeros(f)]  # 1 Hz swing
    noisy = clean + rng.normal(scale=0.01, size=clean.shape) * np.r_[np.full(3, 0.5), np.ones(63)]
    smoothed = retarget.smooth(noisy, retarget.SMOOTH_S * 120)
    inner = slice(20, -20)

    def angle(a, b):  # per bone, radians
        ra = rotations.exp(a[:, 3:].reshape(len(a), -1, 3))
        rb = rotations.exp(b[:, 3:].reshape(len(b), -1, 3))
        return rotations.angle_between(ra, rb)

    assert angle(smoothed, clean)[inner].mean() < 0.4 * angle(noisy, clean)[inner].mean()
    assert np.abs(smoothed - clean)[inner, :3].mean() < 0.4 * np.abs(noisy - clean)[inner, :3].mean()
    # The motion itself passes: the 1 Hz swing keeps its amplitude.
    assert angle(retarget.smooth(clean, retarget.SMOOTH_S * 120), clean)[inner].max() < 0.01
