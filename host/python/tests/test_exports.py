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
