import json
import os
import re
import shutil

import numpy as np
import pytest

from mocap import _core, rotations
from mocap.errors import InputError, TakeError
from mocap.io import calib_toml, take_folder, xsens_csv
from mocap.sim import demo_motion, imu, take_out

PIXEL_TOL, CONFIDENCE_TOL = 0.5e-3 + 1e-9, 0.5e-4 + 1e-9  # the JSON's rounding


@pytest.fixture(scope="module")
def simulated():
    """A short HS take (4 cameras, detections on 2 of every 8 frames, 13 IMUs)."""
    return take_out.simulate(1.0, "hs13", seed=3)


@pytest.fixture(scope="module")
def written(simulated, tmp_path_factory):
    folder = tmp_path_factory.mktemp("take")
    take_folder.write_take(folder, simulated[0])
    take_out.write_truth(folder, simulated[1])
    return folder


@pytest.fixture
def take_dir(written, tmp_path):
    """A copy of the written take, to break."""
    return shutil.copytree(written, tmp_path / "take")


def _assert_rigs_equal(a: _core.Rig, b: _core.Rig) -> None:
    assert [c.name for c in a.cameras] == [c.name for c in b.cameras]
    for x, y in zip(a.cameras, b.cameras):
        assert (x.width, x.height) == (y.width, y.height)
        np.testing.assert_allclose([x.fx, x.fy, x.cx, x.cy], [y.fx, y.fy, y.cx, y.cy], atol=1e-9)
        np.testing.assert_allclose(x.distortion, y.distortion, atol=1e-12)
        np.testing.assert_allclose(x.rotation, y.rotation, atol=1e-9)
        np.testing.assert_allclose(x.translation, y.translation, atol=1e-9)


def test_round_trip_cameras_and_keypoints(simulated, written):
    take, _ = simulated
    back = take_folder.read_take(written)
    assert (back.frame_rate, back.n_frames, back.world_up, back.layout) == (60.0, take.n_frames, "Z", "blazepose33")
    _assert_rigs_equal(back.rig, take.rig)
    counts = {0: 0, 1: 0}
    for cam_in, cam_out in zip(take.people, back.people):
        assert len(cam_out) == take.n_frames
        for sent, read in zip(cam_in, cam_out):
            assert read.shape == sent.shape
            counts[len(read)] += 1
            np.testing.assert_allclose(read[..., :2], sent[..., :2], atol=PIXEL_TOL, rtol=0)
            np.testing.assert_allclose(read[..., 2], sent[..., 2], atol=CONFIDENCE_TOL, rtol=0)
    assert counts[0] > 0 and counts[1] > 0  # frames without detections are "people": []


def test_round_trip_imus_exact_times_and_samples(simulated, written):
    take, _ = simulated
    back = take_folder.read_take(written)
    assert [(s.sensor, s.segment, s.bone) for s in back.imus] == [(s.sensor, s.segment, s.bone) for s in take.imus]
    assert back.imu_rate == 100.0
    for sent, read in zip(take.imus, back.imus):
        assert np.array_equal(read.times_s, sent.times_s)
        np.testing.assert_allclose(read.quaternions, sent.quaternions, atol=2e-9, rtol=0)
        np.testing.assert_allclose(read.accelerations, sent.accelerations, atol=0.6e-6, rtol=0)
        assert np.array_equal(read.packets, np.arange(len(read.times_s)))


def test_imu_orientations_are_in_each_sensors_earth_frame(tmp_path):
    """Without IMU errors, turning each file's quaternions by the truth's heading gives the
    sensor's true orientation: its bone's (from the true skeleton and poses) times the mount."""
    take, truth_in_memory = take_out.simulate(1.0, "hq6", seed=4, imu_errors=imu.ImuErrors(random=False))
    take_folder.write_take(tmp_path, take)
    take_out.write_truth(tmp_path, truth_in_memory)
    back = take_folder.read_take(tmp_path)
    truth = json.loads((tmp_path / "truth.json").read_text())
    skeleton = _core.Skeleton.load(str(tmp_path / truth["skeleton"]))
    poses = demo_motion.interpolate(np.load(tmp_path / truth["thetas"]), back.imus[0].times_s * truth["frame_rate"])
    headings = []
    for s in back.imus:
        t = truth["sensors"][s.sensor]
        assert (t["segment"], t["bone"]) == (s.segment, s.bone)
        headings.append(t["heading_deg"])
        bone = skeleton.bone_names.index(s.bone)
        true = np.array([skeleton.forward_kinematics(p)[0][bone] for p in poses]) @ rotations.exp(np.array(t["mount"]))
        heading = rotations.exp(np.array([0, 0, np.radians(t["heading_deg"])]))
        error = rotations.angle_between(heading @ rotations.matrix_from_quaternion(s.quaternions), true)
        assert error.max() < 1e-6, s.sensor
    assert np.ptp(headings) > 90  # headings differ from sensor to sensor


def test_y_up_takes_rotate_the_calibration_world(simulated, tmp_path):
    take = simulated[0]
    y_up = take_folder.TakeFolder(take.frame_rate, take.n_frames, "Y", take.rig, take.layout, take.people)
    take_folder.write_take(tmp_path, y_up)
    in_file = calib_toml.load(tmp_path / "Calib.toml")
    ours = np.array([c.center() for c in take.rig.cameras])
    theirs = np.array([c.center() for c in in_file.cameras])
    np.testing.assert_allclose(theirs[:, 1], ours[:, 2], atol=1e-9)  # heights on the file's Y
    np.testing.assert_allclose(theirs @ take_folder.WORLD_FROM_Y_UP.T, ours, atol=1e-9)
    assert np.isclose(np.linalg.det(take_folder.WORLD_FROM_Y_UP), 1.0)  # a rotation, not a mirror
    back = take_folder.read_take(tmp_path)
    assert back.world_up == "Y" and back.imus == []
    _assert_rigs_equal(back.rig, take.rig)


def _imu_csv(path, rows, columns, sep="\t"):
    lines = ["// Start Time: Unknown", "// Update Rate: 100.0Hz", sep.join(columns)]
    path.write_text("\r\n".join(lines + [sep.join(str(v) for v in r) for r in rows]) + "\r\n")


def test_counter_and_sample_time_wraps_are_unwrapped(tmp_path):
    n = 70_000  # more than 2^16 packets
    counter = (65_000 + np.arange(n)) % 65_536
    ticks = (2**32 - 3_000_000 + 100 * np.arange(n)) % 2**32  # SampleTimeFine wraps too
    rows = [(f"{c:05d}", t, 1, 0, 0, 0, 0.1, -0.2, 9.81) for c, t in zip(counter, ticks)]
    _imu_csv(tmp_path / "s.txt", rows, ["PacketCounter", "SampleTimeFine", *xsens_csv.QUAT, *xsens_csv.ACC])
    s = xsens_csv.read_imu(tmp_path / "s.txt", 100.0)
    assert np.array_equal(s.packets, 65_000 + np.arange(n))
    assert np.array_equal(s.times_s, (2**32 - 3_000_000 + 100 * np.arange(n, dtype=np.int64)) / 10_000)
    assert np.all(np.diff(s.times_s) > 0)


def test_column_order_and_separator_are_free(tmp_path):
    columns = ["PacketCounter", "SampleTimeFine", *xsens_csv.QUAT, *xsens_csv.ACC]
    rows = [(i, 100 * i, 0.6, 0.8, 0.0, 0.0, 0.5 * i, 1.5, 9.75) for i in range(5)]
    _imu_csv(tmp_path / "a.csv", rows, columns)
    order = [8, 3, 0, 6, 2, 7, 1, 5, 4]
    _imu_csv(tmp_path / "b.csv", [("x", *[str(r[k]).replace(".", ",") for k in order]) for r in rows],
             ["Extra", *[columns[k] for k in order]], sep=";")
    a, b = xsens_csv.read_imu(tmp_path / "a.csv", None), xsens_csv.read_imu(tmp_path / "b.csv", None)
    for field in ("packets", "times_s", "quaternions", "accelerations"):
        assert np.array_equal(getattr(a, field), getattr(b, field))
    np.testing.assert_allclose(a.quaternions[0], [0.6, 0.8, 0, 0])


def test_reads_an_mt_manager_export(shared):
    """The real export has no quaternion and no SampleTimeFine values: Mat[i][j] (sensor ->
    earth) and PacketCounter / rate. At rest the accelerometer reads earth's up."""
    path = sorted((shared / "data" / "imu" / "xsens-mtw-walking").glob("*.txt"))[0]
    s = xsens_csv.read_imu(path, 100.0)
    assert np.allclose(np.diff(s.times_s), 0.01)
    up = np.einsum("nji,j->ni", rotations.matrix_from_quaternion(s.quaternions[:50]), [0, 0, 1.0])
    cos = np.sum(up * s.accelerations[:50], axis=1) / np.linalg.norm(s.accelerations[:50], axis=1)
    assert np.median(cos) > np.cos(np.radians(5))


def _edit(path, old, new, count=1):
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, count))


def _raises(take_dir, file, line=None, column=None, match=None):
    with pytest.raises(TakeError, match=match) as e:
        take_folder.read_take(take_dir)
    assert isinstance(e.value, InputError)  # the CLI prints it, never a traceback
    assert e.value.path == file, str(e.value)
    assert (e.value.line, e.value.column) == (line, column) or (line is None and column is None), str(e.value)
    assert str(e.value).startswith(str(file))
    return e.value


def test_missing_camera(take_dir):
    _edit(take_dir / "take.toml", '"cam2"', '"cam9"')
    _raises(take_dir, take_dir / "Calib.toml", match="no camera 'cam9'")


def test_missing_pose_folder_and_wrong_file_count(take_dir):
    (take_dir / "pose" / "cam4" / "cam4_000000000007_keypoints.json").unlink()
    _raises(take_dir, take_dir / "pose" / "cam4", match="114 JSON files, but take.toml says n_frames = 115")
    shutil.rmtree(take_dir / "pose" / "cam4")
    _raises(take_dir, take_dir / "pose" / "cam4", match="not found")


def test_truncated_json(take_dir):
    path = take_dir / "pose" / "cam2" / "cam2_000000000000_keypoints.json"
    path.write_text(path.read_text()[:100])
    _raises(take_dir, path, 1, 101, match="invalid JSON")


def test_any_bytes_in_a_file_are_a_take_error(take_dir):
    """Inputs the fuzzer found (tests/fuzz/fuzz_take.py) and the caps they led to: bytes that
    are not UTF-8, integers beyond float's range, a camera size that is not a number of
    pixels, more people than a pose file may hold; each is a TakeError naming its file."""
    pose = take_dir / "pose" / "cam2" / "cam2_000000000000_keypoints.json"
    calib = take_dir / "Calib.toml"
    toml_text, calib_text, pose_text = (take_dir / "take.toml").read_text(), calib.read_text(), pose.read_text()
    cases = [(take_dir / "take.toml", toml_text.encode() + b"\n# \xdd\n", "not UTF-8 text"),
             (take_dir / "take.toml", toml_text.replace("n_frames = 115", "n_frames = 1" + "0" * 400).encode(),
              "n_frames"),
             (calib, calib_text.encode() + b"\xff", "codec"),
             (calib, re.sub(r"size = \[[^\]]*\]", "size = [inf, 720]", calib_text, count=1).encode(),
              "malformed field"),
             (calib, re.sub(r"size = \[[^\]]*\]", "size = [1e12, 720]", calib_text, count=1).encode(),
              "is not 1..65536 pixels"),
             (pose, b'{"people": [{"pose_keypoints_2d": [1' + b"0" * 400 + b"]}]}", "is not 99 numbers"),
             (pose, b'{"people": [' + b", ".join([b"{}"] * 101) + b"]}", "101 people")]
    for path, data, what in cases:
        path.write_bytes(data)
        _raises(take_dir, path, match=what)
        path.write_text({take_dir / "take.toml": toml_text, calib: calib_text, pose: pose_text}[path])


def test_wrong_keypoint_count_in_json(take_dir):
    path = take_dir / "pose" / "cam2" / "cam2_000000000000_keypoints.json"
    path.write_text('{"people": [{"pose_keypoints_2d": [1, 2, 0.5]}]}')
    _raises(take_dir, path, match=r"people\[0\].pose_keypoints_2d is not 99 numbers")


@pytest.mark.parametrize("value", ["nan", "NaN", "abc", ""])
def test_bad_number_in_a_csv(take_dir, value):
    path = take_dir / "imu" / "forearm_l.csv"
    lines = path.read_text().splitlines()
    cells = lines[9].split("\t")
    cells[7] = value  # Acc_Y on line 10
    lines[9] = "\t".join(cells)
    path.write_text("\n".join(lines) + "\n")
    _raises(take_dir, path, 10, 8, match="column Acc_Y: .* is not a finite number")


def test_unknown_segment(take_dir):
    _edit(take_dir / "sensors.csv", "upper_back,upper_back", "upper_back,tail")
    _raises(take_dir, take_dir / "sensors.csv", 3, 2, match="unknown segment 'tail'")


def test_missing_column(take_dir):
    path = take_dir / "imu" / "head.csv"
    rows = [ln.split("\t") for ln in path.read_text().splitlines()[2:]]
    path.write_text("\n".join("\t".join(r[:-1]) for r in rows) + "\n")  # no Acc_Z
    _raises(take_dir, path, 1, match="missing column.* Acc_Z")
    _edit(take_dir / "sensors.csv", "sensor,segment,file", "sensor,part,file")
    _raises(take_dir, take_dir / "sensors.csv", 1, match="missing column.* segment")


def test_reordered_columns_read_the_same(take_dir, written):
    path = take_dir / "imu" / "head.csv"
    lines = path.read_text().splitlines()
    order = [6, 7, 8, 2, 3, 4, 5, 1, 0]
    path.write_text("\n".join(lines[:2] + ["\t".join(ln.split("\t")[k] for k in order) for ln in lines[2:]]) + "\n")
    a, b = take_folder.read_take(written).imus[0], take_folder.read_take(take_dir).imus[0]
    assert a.sensor == b.sensor == "head"
    for field in ("packets", "times_s", "quaternions", "accelerations"):
        assert np.array_equal(getattr(a, field), getattr(b, field))


def test_non_increasing_times(take_dir):
    path = take_dir / "imu" / "shin_r.csv"
    _edit(path, "\t2000\t", "\t1900\t")  # sample 20 (line 24: 2 comment lines, the header) at 19's time
    _raises(take_dir, path, 24, 2, match="SampleTimeFine does not increase")


def test_world_up_units_and_layout_are_checked(take_dir):
    _edit(take_dir / "take.toml", 'world_up_axis = "Z"', 'world_up_axis = "X"')
    _raises(take_dir, take_dir / "take.toml", 4, match='world_up_axis: .* is not "Z" or "Y"')
    _edit(take_dir / "take.toml", 'world_up_axis = "X"', 'world_up_axis = "Z"')
    _edit(take_dir / "take.toml", 'units = "m"', 'units = "mm"')
    _raises(take_dir, take_dir / "take.toml", 5, match="units")
    _edit(take_dir / "take.toml", 'units = "mm"', 'units = "m"')
    _edit(take_dir / "take.toml", "BLAZEPOSE_33", "BODY_25")
    _raises(take_dir, take_dir / "take.toml", 11, match="keypoint_layout")
    (take_dir / "take.toml").write_text("[take\nframe_rate = 60")
    _raises(take_dir, take_dir / "take.toml", match="line 1")


@pytest.mark.parametrize("size, message", [("1920", "is not .width, height"), ("[1280, 720]", "but Calib.toml gives")])
def test_image_size_is_checked(take_dir, size, message):
    _edit(take_dir / "take.toml", "image_size = [1920, 1080]", f"image_size = {size}")
    _raises(take_dir, take_dir / "take.toml", 12, match=message)


@pytest.mark.parametrize("where", ["absolute", "dotdot", "symlink"])
def test_paths_out_of_the_take_folder_are_refused(take_dir, tmp_path, where):
    outside = tmp_path / "elsewhere"
    shutil.copytree(take_dir / "pose" / "cam2", outside)
    name = {"absolute": str(outside), "dotdot": "../elsewhere", "symlink": "pose/link"}[where]
    if where == "symlink":
        (take_dir / "pose" / "link").symlink_to(outside)
    _edit(take_dir / "take.toml", '"pose/cam2"', f'"{name}"')
    _raises(take_dir, take_dir / "take.toml", 10, match="pose folder .* is outside the take folder")


def test_an_imu_file_out_of_the_folder_is_refused_without_echoing_it(take_dir, tmp_path):
    secret = tmp_path / "secret.csv"
    secret.write_text("root:x:0:0:root:/root:/bin/bash\n")
    for file in (str(secret), "../secret.csv"):
        (take_dir / "sensors.csv").write_text(f"sensor,segment,file\nhead,head,{file}\n")
        e = _raises(take_dir, take_dir / "sensors.csv", 2, 3, match="IMU file .* is outside the take folder")
        assert "root:x" not in str(e)
    (take_dir / "imu" / "link.csv").symlink_to(secret)  # inside by name, outside once resolved
    (take_dir / "sensors.csv").write_text("sensor,segment,file\nhead,head,imu/link.csv\n")
    assert "root:x" not in str(_raises(take_dir, take_dir / "sensors.csv", 2, 3, match="outside the take folder"))
    _edit(take_dir / "take.toml", 'sensors = "sensors.csv"', f'sensors = "{secret}"')
    _raises(take_dir, take_dir / "take.toml", match=r"\[imu\] sensors .* is outside")


def test_a_nul_byte_in_a_file_name_is_refused_by_name(take_dir):
    """Found by the take folder's fuzzer: a NUL in sensors.csv's file column reached
    os.path.realpath, whose ValueError escaped as a traceback."""
    (take_dir / "sensors.csv").write_text("sensor,segment,file\nhead,head,imu/\x00head.csv\n")
    _raises(take_dir, take_dir / "sensors.csv", 2, 3, match="IMU file .*cannot be resolved")


@pytest.mark.parametrize("file", ["take.toml", "Calib.toml", "sensors.csv", "imu/head.csv",
                                  "pose/cam2/cam2_000000000003_keypoints.json"])
def test_a_fifo_is_refused_without_blocking(take_dir, file):
    path = take_dir / file
    path.unlink()
    os.mkfifo(path)  # opening it for reading would wait for a writer forever
    with pytest.raises(TakeError, match="is not a regular file") as e:
        take_folder.read_take(take_dir)
    assert str(e.value).startswith(str(take_dir))


def test_repeated_cameras_and_pose_folders_are_refused(take_dir):
    _edit(take_dir / "take.toml", '"cam2", "cam4"', '"cam2", "cam2"')
    _raises(take_dir, take_dir / "take.toml", 9, match="camera_names: 'cam2' is named twice")
    _edit(take_dir / "take.toml", '"cam2", "cam2"', '"cam2", "cam4"')
    _edit(take_dir / "take.toml", '"pose/cam2", "pose/cam4"', '"pose/cam2", "pose/./cam2"')
    _raises(take_dir, take_dir / "take.toml", 10, match="pose_dirs: 'pose/./cam2' is named twice")


def test_two_calibration_tables_of_one_name_are_refused(take_dir):
    calib = (take_dir / "Calib.toml").read_text()
    _edit(take_dir / "Calib.toml", 'name = "cam4"', 'name = "cam2"')
    _raises(take_dir, take_dir / "Calib.toml", match="two camera tables are named 'cam2'")
    (take_dir / "Calib.toml").write_text(calib)
    _edit(take_dir / "Calib.toml", 'name = "cam0"', 'name = "cam_02"')  # [cam_01]'s name, [cam_02]'s key
    _edit(take_dir / "take.toml", '"cam0"', '"cam_02"')
    _raises(take_dir, take_dir / "Calib.toml", match="'cam_02' is ambiguous")


def test_a_take_toml_of_random_bytes_is_refused_by_name(take_dir):
    (take_dir / "take.toml").write_bytes(bytes(range(256)) * 4)
    _raises(take_dir, take_dir / "take.toml", match="not UTF-8 text")
