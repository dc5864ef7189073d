import csv
import socket

import bvhio
import numpy as np
import pytest
from pythonosc.osc_bundle import OscBundle

from mocap import _core, paths, rotations
from mocap.io import bvh
from mocap.io.bvh_export import write_bvh
from mocap.io.joints_csv import write_joints_csv
from mocap.io.retarget import P
from mocap.net.vmc import VmcSender

FRAMES = 40
FRAME_RATE = 30.0
POSITION_TOL = 1e-4  # m (0.1 mm)
# BVH frame of the writer: x = our y (left), y = our z (up), z = our x (forward), centimetres.
TO_BVH_CM = 100.0 * P.T
# Unity: x = right = -our y, y = up = our z, z = forward = our x (left-handed).
TO_UNITY = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
# Unity's humanoid hierarchy for the bones sent (no UpperChest), and its root.
UNITY_PARENT = {
    "Hips": "root", "Spine": "Hips", "Chest": "Spine", "Neck": "Chest", "Head": "Neck",
    **{f"{side}{bone}": parent.format(side=side) for side in ("Left", "Right") for bone, parent in (
        ("Shoulder", "Chest"), ("UpperArm", "{side}Shoulder"), ("LowerArm", "{side}UpperArm"),
        ("Hand", "{side}LowerArm"), ("UpperLeg", "Hips"), ("LowerLeg", "{side}UpperLeg"),
        ("Foot", "{side}LowerLeg"), ("Toes", "{side}Foot"))},
}
OURS = {"Hips": "pelvis", "Spine": "spine_lower", "Chest": "spine_upper", "Neck": "neck", "Head": "head",
        **{f"{side}{unity}": f"{ours}_{side[0].lower()}" for side in ("Left", "Right") for unity, ours in (
            ("Shoulder", "clavicle"), ("UpperArm", "upper_arm"), ("LowerArm", "forearm"), ("Hand", "hand"),
            ("UpperLeg", "thigh"), ("LowerLeg", "shin"), ("Foot", "foot"), ("Toes", "toes"))}}

# Left thigh: BVH Euler (z, x, y) = (ALPHA, sweep, GAMMA), the sweep through gimbal lock at x = 90.
ALPHA, GAMMA = 20.0, -35.0
SWEEP = np.concatenate([np.linspace(0.0, 85.0, 18), [89.9999, 89.9999999, 90.0, 90.0000001, 90.0001],
                        np.linspace(95.0, 130.0, FRAMES - 23)])
YAW_STEP = 25.0  # degrees per frame of root yaw: 975 degrees over the clip


@pytest.fixture(scope="module")
def skeleton():
    return _core.Skeleton.load(str(paths.DEFAULT_SKELETON))


def _axis(angle_deg, axis):
    return rotations.exp(np.radians(angle_deg)[..., None] * np.eye(3)[axis])


@pytest.fixture(scope="module")
def thetas(skeleton):
    """Smooth random joint rotations (<= 45 deg), a walking, spinning root, a thigh through gimbal lock."""
    rng = np.random.default_rng(7)
    s = np.linspace(0.0, 1.0, FRAMES)[:, None, None]
    start, end = (rng.normal(size=(2, skeleton.num_bones, 3)) * 0.3).clip(-0.45, 0.45)
    thetas = np.zeros((FRAMES, skeleton.pose_dim))
    thetas[:, 3:] = ((1 - s) * start + s * end).reshape(FRAMES, -1)
    thetas[:, :3] = np.stack([np.linspace(-1.0, 2.0, FRAMES), 0.3 * np.sin(s[:, 0, 0] * 6),
                              0.95 + 0.03 * np.cos(s[:, 0, 0] * 20)], axis=1)
    thetas[:, 3:6] = np.outer(np.radians(YAW_STEP) * np.arange(FRAMES), [0.0, 0.0, 1.0])  # about up
    zxy_bvh = _axis(np.full(FRAMES, ALPHA), 2) @ _axis(SWEEP, 0) @ _axis(np.full(FRAMES, GAMMA), 1)
    thigh = 3 + 3 * skeleton.bone_index("thigh_l")
    thetas[:, thigh:thigh + 3] = rotations.log(P @ zxy_bvh @ P.T)
    return thetas


@pytest.fixture(scope="module")
def fk(skeleton, thetas):
    poses = [skeleton.forward_kinematics(t) for t in thetas]
    return np.stack([r for r, _ in poses]), np.stack([p for _, p in poses])


@pytest.fixture(scope="module")
def bvh_path(tmp_path_factory, skeleton, thetas):
    path = tmp_path_factory.mktemp("bvh") / "take.bvh"
    write_bvh(path, skeleton, thetas, FRAME_RATE)
    return path


def test_bvh_own_parser_reproduces_forward_kinematics(skeleton, fk, bvh_path):
    motion = bvh.load(bvh_path)
    names = skeleton.bone_names
    assert [j.name for j in motion.joints] == names  # the default skeleton is depth first
    assert [j.parent for j in motion.joints] == skeleton.parents
    assert motion.frame_time == pytest.approx(1.0 / FRAME_RATE)
    assert {j.name for j in motion.joints if j.end_site is not None} == {"head", "hand_l", "hand_r", "toes_l", "toes_r"}
    rot, pos = motion.global_transforms()
    assert pos.shape[0] == FRAMES
    np.testing.assert_allclose(pos / 100.0, fk[1] @ TO_BVH_CM.T / 100.0, atol=POSITION_TOL / 10)
    np.testing.assert_allclose(rot, P.T @ fk[0] @ P, atol=1e-7)


def test_bvh_independent_reader_reproduces_forward_kinematics(skeleton, fk, bvh_path):
    root = bvhio.readAsHierarchy(str(bvh_path))
    joints = [j for j, _, _ in root.layout()]
    assert sorted(j.Name for j in joints) == sorted(skeleton.bone_names)
    index = [skeleton.bone_index(j.Name) for j in joints]
    worst = 0.0
    for frame in range(FRAMES):
        root.loadPose(frame)
        got = np.array([list(j.PositionWorld) for j in joints]) / 100.0
        want = fk[1][frame, index] @ TO_BVH_CM.T / 100.0
        worst = max(worst, np.abs(got - want).max())
    assert worst < POSITION_TOL


def _channels(motion, name):
    col = sum(len(j.channels) for j in motion.joints[: motion.index(name)])
    joint = motion.joints[motion.index(name)]
    return {ch: motion.values[:, col + k] for k, ch in enumerate(joint.channels)}


def test_bvh_euler_angles_are_exact_through_gimbal_lock_and_continuous(bvh_path):
    motion = bvh.load(bvh_path)
    thigh = _channels(motion, "thigh_l")
    np.testing.assert_allclose(thigh["Zrotation"], ALPHA, atol=1e-4)
    np.testing.assert_allclose(thigh["Xrotation"], SWEEP, atol=1e-4)  # past 90, not folded back
    np.testing.assert_allclose(thigh["Yrotation"], GAMMA, atol=1e-4)
    root = _channels(motion, "pelvis")
    np.testing.assert_allclose(root["Yrotation"], YAW_STEP * np.arange(FRAMES), atol=1e-4)  # unwrapped
    rotation_columns = [c for j in motion.joints for c in j.channels]
    steps = np.abs(np.diff(motion.values, axis=0))[:, [c.endswith("rotation") for c in rotation_columns]]
    assert steps.max() <= YAW_STEP + 1e-3


def test_bvh_rejects_non_finite_pose_naming_the_frame(tmp_path, skeleton, thetas):
    bad = thetas.copy()
    bad[5, 17] = np.nan
    path = tmp_path / "bad.bvh"
    with pytest.raises(ValueError, match="frame 5"):
        write_bvh(path, skeleton, bad, FRAME_RATE)
    assert not path.exists()


def test_joints_csv_holds_forward_kinematics(tmp_path, skeleton, thetas, fk):
    path = tmp_path / "joints.csv"
    times = 10.0 + np.arange(FRAMES) / FRAME_RATE
    write_joints_csv(path, skeleton, thetas, times)
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["frame", "time_s"] + [f"{b}_{a}" for b in skeleton.bone_names for a in "xyz"]
    values = np.array(rows[1:], dtype=float)
    np.testing.assert_array_equal(values[:, 0], np.arange(FRAMES))
    np.testing.assert_allclose(values[:, 1], times, atol=1e-6)
    np.testing.assert_allclose(values[:, 2:], fk[1].reshape(FRAMES, -1), atol=1e-6)
    thetas = thetas.copy()
    thetas[3, 0] = np.inf
    with pytest.raises(ValueError, match="frame 3"):
        write_joints_csv(path, skeleton, thetas, times)


@pytest.fixture
def receiver():
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(2.0)
    yield sock
    sock.close()


def _receive_frame(skeleton, receiver, theta, time_s):
    with VmcSender(skeleton, port=receiver.getsockname()[1]) as sender:
        assert sender.send(theta, time_s)
        assert (sender.sent, sender.failures, sender.skipped) == (1, 0, 0)
    data = receiver.recv(65536)
    assert OscBundle.dgram_is_bundle(data)
    return list(OscBundle(data))


def _unity_pose(message):
    p = np.array(message.params[1:4])
    x, y, z, w = message.params[4:8]
    return p, rotations.matrix_from_quaternion([w, x, y, z])


def test_vmc_frame_reproduces_forward_kinematics(skeleton, thetas, receiver):
    theta = thetas[27]
    messages = _receive_frame(skeleton, receiver, theta, 1.25)
    assert [m.address for m in messages[:3]] == ["/VMC/Ext/OK", "/VMC/Ext/T", "/VMC/Ext/Root/Pos"]
    assert messages[0].params == [1] and isinstance(messages[0].params[0], int)
    assert messages[1].params[0] == pytest.approx(1.25)
    assert messages[2].params[0] == "root"
    bones = {m.params[0]: m for m in messages[3:] if m.address == "/VMC/Ext/Bone/Pos"}
    assert len(messages) == 3 + len(bones) and set(bones) == set(UNITY_PARENT)

    world = {"root": _unity_pose(messages[2])}
    for name in UNITY_PARENT:  # parents come first in UNITY_PARENT
        parent_p, parent_r = world[UNITY_PARENT[name]]
        p, r = _unity_pose(bones[name])
        world[name] = (parent_p + parent_r @ p, parent_r @ r)
    rot, pos = skeleton.forward_kinematics(theta)
    np.testing.assert_allclose(TO_UNITY.T @ world["root"][0], pos[0] * [1, 1, 0], atol=1e-6)
    for name, (p, r) in world.items():
        if name == "root":
            continue
        b = skeleton.bone_index(OURS[name])
        np.testing.assert_allclose(TO_UNITY.T @ p, pos[b], atol=1e-5, err_msg=name)
        np.testing.assert_allclose(TO_UNITY.T @ r @ TO_UNITY, rot[b], atol=1e-5, err_msg=name)


def test_vmc_axes_follow_unity_conventions(skeleton, receiver):
    theta = np.zeros(skeleton.pose_dim)
    theta[5] = np.pi / 2  # root turns a quarter to its left (about our +z, up)
    theta[2] = 0.95
    bones = {m.params[0]: m for m in _receive_frame(skeleton, receiver, theta, 0.0)[3:]}
    p_hips, r_hips = _unity_pose(bones["Hips"])
    np.testing.assert_allclose(p_hips, [0.0, 0.95, 0.0], atol=1e-6)  # height on Unity's y
    # Facing +z, turning left faces -x: Unity's (left-handed) -90 deg about +y.
    np.testing.assert_allclose(r_hips @ [0, 0, 1], [-1, 0, 0], atol=1e-6)
    x, y, z, w = bones["Hips"].params[4:8]
    assert abs(y) == pytest.approx(np.sqrt(0.5), abs=1e-6) and np.sign(y) != np.sign(w)
    # Left limbs at -x, toes forward (+z) of the foot in the rest pose.
    assert bones["LeftUpperLeg"].params[1] < 0 and bones["LeftUpperArm"].params[1] < 0
    assert bones["RightUpperLeg"].params[1] > 0 and bones["LeftToes"].params[3] > 0


def test_vmc_send_failures_are_counted_not_raised(skeleton):
    free = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    free.bind(("127.0.0.1", 0))
    port = free.getsockname()[1]
    free.close()
    theta = np.zeros(skeleton.pose_dim)
    sender = VmcSender(skeleton, port=port)  # nobody listens
    for _ in range(3):
        sender.send(theta, 0.0)
    assert sender.failures + sender.sent == 3
    assert not sender.send(np.full(skeleton.pose_dim, np.nan), 0.0) and sender.skipped == 1
    sender.close()
    assert not sender.send(theta, 0.0) and sender.failures >= 1
    refused = VmcSender(skeleton, host="255.255.255.255", port=port)  # broadcast, not enabled: EACCES
    assert not refused.send(theta, 0.0) and refused.failures == 1
    refused.close()


def test_vmc_values_beyond_float32_are_skipped_not_raised(skeleton):
    """Inputs the fuzzer found (tests/fuzz/fuzz_vmc.py): a finite root position or time beyond
    float32's range, which OSC's 'f' cannot carry, made struct raise OverflowError."""
    with VmcSender(skeleton, port=9) as sender:
        far = np.zeros(skeleton.pose_dim)
        far[0] = 1e39
        assert not sender.send(far, 0.0) and sender.skipped == 1
        assert not sender.send(np.zeros(skeleton.pose_dim), 1e39) and sender.skipped == 2


def test_positions_csv_writes_published_bones_and_refuses_what_is_not_finite(tmp_path, skeleton, fk):
    """The bones as the host published them (each frame with the calibration in use then)."""
    from mocap.io.joints_csv import write_positions_csv

    path = tmp_path / "published.csv"
    positions = fk[1].reshape(FRAMES, -1, 3)
    write_positions_csv(path, skeleton.bone_names, positions, np.arange(FRAMES) / FRAME_RATE)
    with open(path, newline="") as f:
        values = np.array(list(csv.reader(f))[1:], dtype=float)
    np.testing.assert_allclose(values[:, 2:], positions.reshape(FRAMES, -1), atol=1e-6)
    bad = positions.copy()
    bad[4, 2, 1] = np.nan
    with pytest.raises(ValueError, match="frame 4: position"):
        write_positions_csv(path, skeleton.bone_names, bad, np.arange(FRAMES) / FRAME_RATE)
    with pytest.raises(ValueError, match="positions must be"):
        write_positions_csv(path, skeleton.bone_names, positions[:, :5], np.arange(FRAMES) / FRAME_RATE)
