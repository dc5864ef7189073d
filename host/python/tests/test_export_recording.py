"""`mocap export` of a recorded live take: the poses mocapd published (/pose), not solved again,
in every format; BVH and glTF with the skeleton they were solved with (the latest recorded
calibration's, else the attached session's); a recording without poses says so."""

import dataclasses
import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from mocap import _core, paths
from mocap.io import bvh, retarget
from mocap.io.joints_csv import read_positions_csv
from mocap.io.session import Session
from mocap.net import wire
from mocap.recording import recorder

T0 = 1_700_000_000_000_000_000
FRAMES = 12


def _session(folder):
    camera = _core.Camera()
    camera.name, camera.width, camera.height, camera.fx, camera.fy, camera.cx, camera.cy = "cam1", 640, 480, 500, 500, 320, 240
    camera.translation = [0.0, 0.0, 4.0]
    (folder / "rig.json").write_text(_core.Rig([camera]).to_json())
    for name, source in (("skeleton.json", paths.DEFAULT_SKELETON), ("layout.json", paths.HOST_DATA / "layouts" /
                         "blazepose33.json"), ("imus.json", paths.HOST_DATA / "imus13.json")):
        shutil.copyfile(source, folder / name)
    session = Session(skeleton="skeleton.json", rig="rig.json", layout="layout.json", imus="imus.json",
                      inputs=["tcp://127.0.0.1:5600"], output="tcp://*:5700", base=folder)
    return session.save(folder / "session.json")


def _poses(skeleton):
    rng = np.random.default_rng(4)
    thetas = np.zeros((FRAMES, skeleton.pose_dim))
    thetas[:, :3] = [0.2, 0.1, 1.0] + np.linspace(0, 1, FRAMES)[:, None] * [0.4, 0.0, 0.0]
    thetas[:, 3:] = 0.3 * rng.normal(size=(1, skeleton.pose_dim - 3)) * np.linspace(0.3, 1, FRAMES)[:, None]
    poses = []
    for k, theta in enumerate(thetas):
        _, origins = skeleton.forward_kinematics(theta)
        pose = wire.PoseFrame(capture_time_ns=T0 + k * 16_666_667, frame_index=k, theta=list(theta))
        for name, (x, y, z) in zip(skeleton.bone_names, origins):
            pose.joints.add(name=name, px=x, py=y, pz=z, qw=1.0)
        poses.append(pose)
    return thetas, poses


def _export(*args):
    return subprocess.run([sys.executable, "-m", "mocap.cli", "export", *map(str, args)], capture_output=True,
                          text=True)


@pytest.fixture
def recorded(tmp_path):
    """A recording of a live take whose skeleton a live calibration changed: 12 poses (one of them
    received twice), the calibration, inputs and Health beside them."""
    session = _session(tmp_path)
    longer = json.loads(paths.DEFAULT_SKELETON.read_text())  # the calibration found every bone 10% longer
    for bone in longer["bones"]:
        bone["offset"] = [1.1 * v for v in bone["offset"]]
    calibrated = _core.Skeleton.from_json(json.dumps(longer))
    thetas, poses = _poses(calibrated)
    path = tmp_path / "take.mcap"
    with recorder.Recorder(path) as r:
        r.attach_session(session)
        calibration = wire.Calibration(source="cal", sequence=1, valid_from_ns=T0, skeleton_json=calibrated.to_json(),
                                       imus_json=(tmp_path / "imus.json").read_text(),
                                       layout_json=(tmp_path / "layout.json").read_text())
        assert r.write(wire.encode(calibration), T0)
        for k, pose in enumerate(poses):
            r.write(wire.encode(wire.KeypointFrame(camera_id="cam1", capture_time_ns=pose.capture_time_ns)), T0 + k)
            r.write(wire.encode(pose), pose.capture_time_ns + 2_000_000)
        r.write(wire.encode(poses[5]), poses[5].capture_time_ns + 3_000_000)  # received twice
        r.write(wire.encode(wire.Health(source="host", time_ns=T0)), T0)
    return path, calibrated, thetas, poses


def test_a_recorded_take_exports_its_published_poses_in_every_format(recorded, tmp_path):
    path, skeleton, thetas, poses = recorded
    published = np.array([[[j.px, j.py, j.pz] for j in p.joints] for p in poses])
    out = _export(path, "--format", "csv", "--out", tmp_path / "joints.csv")
    assert out.returncode == 0, out.stderr
    names, positions, times = read_positions_csv(tmp_path / "joints.csv")
    assert names == skeleton.bone_names and positions.shape == (FRAMES, skeleton.num_bones, 3)  # the repeat once
    assert np.abs(positions - published).max() < 1e-6 and np.allclose(times, np.arange(FRAMES) / 60.0, atol=1e-5)

    out = _export(path, "--format", "bvh", "--out", tmp_path / "take.bvh")
    assert out.returncode == 0, out.stderr
    motion = bvh.load(tmp_path / "take.bvh")
    _, global_cm = motion.global_transforms()
    joints = [motion.index(n) for n in skeleton.bone_names]
    # the calibrated skeleton's: the session's would put the joints 10% off
    assert np.abs(global_cm[:, joints] / 100.0 @ retarget.P.T - published).max() < 1e-4
    assert abs(1.0 / motion.frame_time - 60.0) < 1e-3

    for fmt, file in (("gltf", "take.glb"), ("trc", "take.trc"), ("c3d", "take.c3d")):
        out = _export(path, "--format", fmt, "--out", tmp_path / file)
        assert out.returncode == 0, out.stderr
        assert json.loads(out.stdout)["frames"] == FRAMES, out.stdout


def test_a_recording_without_poses_or_a_bvh_as_positions_is_refused(tmp_path):
    with recorder.Recorder(tmp_path / "inputs.mcap") as r:
        r.write(wire.encode(wire.KeypointFrame(camera_id="cam1", capture_time_ns=T0)), T0)
    out = _export(tmp_path / "inputs.mcap", "--format", "csv", "--out", tmp_path / "x.csv")
    assert out.returncode == 2 and "no solved poses (/pose) in this recording" in out.stderr, out.stderr
    (tmp_path / "take.bvh").write_text("HIERARCHY\n")
    out = _export(tmp_path / "take.bvh", "--format", "trc", "--out", tmp_path / "x.trc")
    assert out.returncode == 2 and "trc is exported from a joint CSV" in out.stderr, out.stderr


def test_poses_of_several_people_are_written_a_file_per_person(tmp_path):
    from mocap.recording import offline

    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    _, poses = _poses(skeleton)
    for k, pose in enumerate(poses):
        pose.subject_id = 1 + k % 2
    written = offline.write_poses(poses, skeleton, tmp_path / "take.bvh", tmp_path / "joints.csv")
    assert [f.name for f in written] == ["take_subject1.bvh", "joints_subject1.csv", "take_subject2.bvh",
                                         "joints_subject2.csv"]
    assert not (tmp_path / "take.bvh").exists()
    for subject in (1, 2):
        _, positions, _ = read_positions_csv(tmp_path / f"joints_subject{subject}.csv")
        mine = [p for p in poses if p.subject_id == subject]
        assert np.abs(positions - np.array([[[j.px, j.py, j.pz] for j in p.joints] for p in mine])).max() < 1e-6
        assert bvh.load(tmp_path / f"take_subject{subject}.bvh").num_frames == FRAMES // 2


def test_a_recording_of_several_people_exports_a_file_per_person(tmp_path):
    """Two people on the same frames (subject 1 in a suit whose skeleton is 10% longer, subject 2
    from video, from the fourth frame): a BVH each with its own skeleton, or one person's CSV."""
    session = Session.load(_session(tmp_path))
    longer = json.loads(paths.DEFAULT_SKELETON.read_text())
    for bone in longer["bones"]:
        bone["offset"] = [1.1 * v for v in bone["offset"]]
    (tmp_path / "suit_skeleton.json").write_text(json.dumps(longer))
    session = dataclasses.replace(session, people=2, suits=[{"imus": "imus.json", "skeleton": "suit_skeleton.json"}])
    session.save(tmp_path / "session.json")
    suit_skeleton = _core.Skeleton.from_json(json.dumps(longer))
    sensors = [s.name for s in _core.load_imu_sites(str(tmp_path / "imus.json"), suit_skeleton)]
    _, suited = _poses(suit_skeleton)
    _, unsuited = _poses(_core.Skeleton.load(str(paths.DEFAULT_SKELETON)))
    for pose in suited:
        pose.subject_id = 1
        pose.imus.extend(sensors)
    for pose in unsuited:
        pose.subject_id = 2
    path = tmp_path / "take.mcap"
    with recorder.Recorder(path) as r:
        r.attach_session(tmp_path / "session.json")
        for k in range(FRAMES):
            for pose in [suited[k]] + ([unsuited[k]] if k >= 3 else []):
                r.write(wire.encode(pose), pose.capture_time_ns + 2_000_000)
    (tmp_path / "suit_skeleton.json").unlink()  # the recording holds what it needs

    out = _export(path, "--format", "bvh", "--out", tmp_path / "take.bvh")
    assert out.returncode == 0, out.stderr
    subjects = json.loads(out.stdout)["subjects"]
    assert {s: v["frames"] for s, v in subjects.items()} == {"1": FRAMES, "2": FRAMES - 3}, out.stdout
    for file, skeleton, poses in (("take_subject1.bvh", suit_skeleton, suited),
                                  ("take_subject2.bvh", None, unsuited[3:])):
        motion = bvh.load(tmp_path / file)
        _, global_cm = motion.global_transforms()
        published = np.array([[[j.px, j.py, j.pz] for j in p.joints] for p in poses])
        names = [j.name for j in poses[0].joints]
        assert np.abs(global_cm[:, [motion.index(n) for n in names]] / 100.0 @ retarget.P.T - published).max() < 1e-4

    out = _export(path, "--format", "csv", "--subject", "2", "--out", tmp_path / "two.csv")
    assert out.returncode == 0, out.stderr
    _, positions, times = read_positions_csv(tmp_path / "two.csv")
    assert positions.shape[0] == FRAMES - 3 and not (tmp_path / "two_subject1.csv").exists()
    assert abs(times[0] - 3 / 60.0) < 1e-5  # on the take's clock: they came in on its fourth frame
    out = _export(path, "--format", "csv", "--subject", "5", "--out", tmp_path / "five.csv")
    assert out.returncode == 2 and "no subject 5 in this take (subjects: 1, 2)" in out.stderr, out.stderr
