"""`mocap export`: a solve's joint positions as TRC (OpenSim, Pose2Sim) and C3D, read back by
readers the project did not write (the `c3d` package and ezc3d for C3D; OpenSim's TRC rules,
checked cell by cell, and our reader for TRC)."""

import subprocess
import sys

import c3d
import ezc3d
import numpy as np
import pytest

from mocap import _core, paths
from mocap.errors import InputError
from mocap.io import retarget
from mocap.io.c3d_export import write_c3d
from mocap.io.joints_csv import read_positions_csv, write_joints_csv
from mocap.io.trc import POSE2SIM_MARKERS, read_trc, write_trc

pytestmark = pytest.mark.filterwarnings("ignore:No analog data found")  # the c3d reader on a markers-only file


def _export(*args):
    return subprocess.run([sys.executable, "-m", "mocap.cli", "export", *map(str, args)], capture_output=True,
                          text=True)


@pytest.fixture
def joints(tmp_path):
    """A joint CSV of a walking skeleton (bone origins, our world: Z up), 30 frames at 60 Hz."""
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    thetas = np.zeros((30, skeleton.pose_dim))
    thetas[:, 0] = np.linspace(0.0, 0.5, 30)  # walks 0.5 m along x
    thetas[:, 2] = 1.0  # every bone origin above the floor
    path = tmp_path / "joints.csv"
    write_joints_csv(path, skeleton, thetas, np.arange(30) / 60.0)
    return path


def test_a_c3d_export_is_read_back_by_two_independent_readers(joints, tmp_path):
    names, positions, _ = read_positions_csv(joints)
    out = _export(joints, "--format", "c3d", "--out", tmp_path / "take.c3d")
    assert out.returncode == 0, out.stderr
    with open(tmp_path / "take.c3d", "rb") as f:
        reader = c3d.Reader(f)
        assert [n.strip() for n in reader.point_labels] == names and reader.point_rate == 60.0
        assert reader.get("POINT:UNITS").string_value.strip() == "mm"
        read = np.array([points[:, :3] for _, points, _ in reader.read_frames()]) / 1000.0
    np.testing.assert_allclose(read, positions, atol=1e-6)  # float32 millimetres
    e = ezc3d.c3d(str(tmp_path / "take.c3d"))
    np.testing.assert_allclose(e["data"]["points"][:3].transpose(2, 1, 0) / 1000.0, positions, atol=1e-6)


def test_a_missing_marker_is_marked_as_c3d_marks_one(tmp_path):
    markers = np.ones((3, 2, 3))
    markers[1, 0] = np.nan
    write_c3d(tmp_path / "m.c3d", ["a", "b"], markers, 100.0)
    with open(tmp_path / "m.c3d", "rb") as f:
        residuals = [points[:, 3] for _, points, _ in c3d.Reader(f).read_frames()]
    assert residuals[1][0] == -1 and residuals[1][1] >= 0 and residuals[0][0] >= 0


def test_a_trc_export_follows_opensims_rules_in_pose2sims_axes_and_names(joints, tmp_path):
    names, positions, times = read_positions_csv(joints)
    out = _export(joints, "--format", "trc", "--out", tmp_path / "take.trc")
    assert out.returncode == 0, out.stderr
    lines = (tmp_path / "take.trc").read_text().splitlines()
    header = dict(zip(lines[1].split("\t"), lines[2].split("\t")))
    assert header["DataRate"] == "60" and header["NumFrames"] == "30" and header["Units"] == "m"
    labels = lines[3].split("\t")
    assert labels[:2] == ["Frame#", "Time"] and all(c == "" for k, c in enumerate(labels[2:]) if k % 3)
    assert labels[2::3] == [POSE2SIM_MARKERS.get(n, n) for n in names]
    assert lines[4].split("\t")[2:5] == ["X1", "Y1", "Z1"] and len(lines) == 5 + 30
    trc = read_trc(tmp_path / "take.trc")
    np.testing.assert_allclose(trc.markers @ retarget.P.T, positions, atol=1e-6)  # Y up in the file
    np.testing.assert_allclose(trc.times, times, atol=1e-6)
    assert (trc.markers[:, :, 1] > 0).all()  # every joint above the floor: up is the file's Y


def test_a_missing_trc_marker_is_an_empty_cell(tmp_path):
    markers = np.arange(12.0).reshape(2, 2, 3)
    markers[0, 1] = np.nan
    write_trc(tmp_path / "m.trc", ["a", "b"], markers, 50.0, units="mm")
    row = (tmp_path / "m.trc").read_text().splitlines()[5].split("\t")
    assert row[5:8] == ["", "", ""] and float(row[2]) == 0.0
    back = read_trc(tmp_path / "m.trc")
    assert np.isnan(back.markers[0, 1]).all() and np.allclose(back.markers[1], markers[1])


@pytest.mark.parametrize("text, says", [
    ("frame,time_s,a_x,a_y\n0,0,1,2\n", ":1: expected frame, time_s"),
    ("frame,time_s,a_x,a_y,a_z\n0,0,1,2,x\n", ":2: 5 cells, expected 5 numbers"),
    ("frame,time_s,a_x,a_y,a_z\n0,0,1,2,3\n1,0,1,2,3\n", "time_s does not increase"),
    ("frame,time_s,a_x,a_y,a_z\n0,0,1,2,nan\n", ":2: not finite"),
    ("frame,time_s,a_x,a_y,a_z\n", "no frames"),
])
def test_a_bad_joint_csv_is_refused_with_its_line(tmp_path, text, says):
    (tmp_path / "j.csv").write_text(text)
    with pytest.raises(InputError, match=says):
        read_positions_csv(tmp_path / "j.csv")
    out = _export(tmp_path / "j.csv", "--format", "trc", "--out", tmp_path / "o.trc")
    assert out.returncode != 0 and says.split(":")[-1].strip()[:10] in out.stderr and "Traceback" not in out.stderr


def test_export_of_a_folder_without_a_solve_says_so(tmp_path):
    out = _export(tmp_path, "--format", "c3d", "--out", tmp_path / "o.c3d")
    assert out.returncode != 0 and "joints.csv: no such file" in out.stderr and "Traceback" not in out.stderr


def _read_glb(path):
    """(the JSON, accessor index -> array) of a binary glTF, read from the spec's layout alone."""
    import json
    import struct
    data = path.read_bytes()
    magic, version, length = struct.unpack_from("<4sII", data)
    assert magic == b"glTF" and version == 2 and length == len(data)
    (json_length,) = struct.unpack_from("<I", data, 12)
    doc = json.loads(data[20:20 + json_length])
    (bin_length,) = struct.unpack_from("<I", data, 20 + json_length)
    blob = data[28 + json_length: 28 + json_length + bin_length]
    sizes = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}
    types = {5126: np.float32, 5123: np.uint16}

    def accessor(i):
        a = doc["accessors"][i]
        view = doc["bufferViews"][a["bufferView"]]
        n = a["count"] * sizes[a["type"]]
        return np.frombuffer(blob, types[a["componentType"]], n, view.get("byteOffset", 0)).reshape(a["count"], -1)
    return doc, accessor


def _quaternion_matrix(q):
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def test_a_gltf_export_animates_the_solved_skeleton(tmp_path):
    from mocap.io.bvh_export import write_bvh
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    rng = np.random.default_rng(1)
    thetas = np.zeros((12, skeleton.pose_dim))
    thetas[:, :3] = [0.3, -0.2, 1.0] + np.linspace(0, 1, 12)[:, None] * [0.5, 0.1, 0.0]
    thetas[:, 3:] = 0.4 * rng.normal(size=(1, skeleton.pose_dim - 3)) * np.linspace(0.2, 1, 12)[:, None]
    write_bvh(tmp_path / "take.bvh", skeleton, thetas, 60.0)
    out = _export(tmp_path / "take.bvh", "--format", "gltf", "--out", tmp_path / "take.glb")
    assert out.returncode == 0, out.stderr
    doc, accessor = _read_glb(tmp_path / "take.glb")
    nodes, (animation,) = doc["nodes"], doc["animations"]
    bones = {n["name"]: i for i, n in enumerate(nodes) if n["name"] in skeleton.bone_names}
    assert len(bones) == skeleton.num_bones
    parent = {c: i for i, n in enumerate(nodes) for c in n.get("children", [])}
    tracks = {(c["target"]["node"], c["target"]["path"]): animation["samplers"][c["sampler"]]
              for c in animation["channels"]}
    times = accessor(tracks[(bones["pelvis"], "rotation")]["input"]).ravel()
    np.testing.assert_allclose(times, np.arange(12) / 60.0, atol=1e-6)
    for k, theta in enumerate(thetas):
        world = {}
        for i in sorted(bones.values()):  # parents first, as in the skeleton
            node = nodes[i]
            r = _quaternion_matrix(accessor(tracks[(i, "rotation")]["output"])[k].astype(float))
            t = (accessor(tracks[(i, "translation")]["output"])[k] if (i, "translation") in tracks
                 else np.array(node.get("translation", [0, 0, 0])))
            if i in parent:
                pr, pt = world[parent[i]]
                world[i] = (pr @ r, pt + pr @ t)
            else:
                world[i] = (r, t)
        _, expected = skeleton.forward_kinematics(theta)
        got = np.array([world[bones[b]][1] for b in skeleton.bone_names]) @ retarget.P.T  # glTF's Y up -> ours
        assert np.abs(got - expected).max() < 1e-3, k
    (skin,) = doc["skins"]
    inverse_bind = accessor(skin["inverseBindMatrices"]).reshape(-1, 4, 4).transpose(0, 2, 1)  # column-major
    _, rest = skeleton.forward_kinematics(np.zeros(skeleton.pose_dim))
    rest_of_joint = rest[[skeleton.bone_names.index(nodes[i]["name"]) for i in skin["joints"]]]
    np.testing.assert_allclose(inverse_bind[:, :3, 3], -rest_of_joint @ retarget.P, atol=1e-6)
    weights = accessor(doc["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"])
    assert np.allclose(weights.sum(axis=1), 1.0) and skin["joints"] == sorted(bones.values())
