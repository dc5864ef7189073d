"""`mocap calibrate-rig`: the cameras' poses from the person in view, no board — on a
simulated take (every camera's pose known) and on Pose2Sim's real Balancing trial (its own
Qualisys board calibration as the reference); bad input ends with the reason."""

import json

import numpy as np
import pytest

from mocap import _core, rotations
from mocap.calibration.rig import calibrate, compare, world
from mocap.cli.main import main
from mocap.errors import InputError
from mocap.eval import balancing_take
from mocap.io import calib_toml, take_folder
from mocap.io.demo_data import TRIAL_CACHE, TRIAL_DONE
from mocap.sim import take_out


def aligned_errors(estimated, truth) -> tuple[float, np.ndarray, np.ndarray, float]:
    """Scale (truth / estimate), per camera centre distance (cm) and orientation angle (deg), and
    the up axes' angle (deg), after the similarity of the camera centres (mocap.calibration.rig.compare)."""
    found = compare.compare(estimated, truth)
    cm = np.array([c["position_cm"] for c in found["cameras"].values()])
    deg = np.array([c["orientation_deg"] for c in found["cameras"].values()])
    return 1 / (1 + found["scale_error_pct"] / 100), cm, deg, found["up_deg"]


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rig") / "take"
    take_out.run(folder, 10.0, layout="body25b")
    return take_folder.read_take(folder), folder


def test_the_comparison_finds_a_known_similarity_and_a_turned_camera(simulated):
    truth = simulated[0].rig
    turn, shift, scale = rotations.exp([0.1, -0.2, 0.3]), np.array([1.0, 2.0, -0.5]), 1.3
    moved = []
    for i, cam in enumerate(truth.cameras):  # the rig in a world X' = scale turn X + shift
        copy = _core.Rig.from_json(_core.Rig([cam]).to_json()).cameras[0]
        centre = scale * turn @ compare.centres(_core.Rig([cam]))[0] + shift
        rotation = np.asarray(cam.rotation) @ turn.T
        if i == 1:  # this one also turned 2 degrees about its optical axis
            rotation = rotations.exp([0.0, 0.0, np.radians(2.0)]) @ rotation
        copy.rotation, copy.translation = rotation, -rotation @ centre
        moved.append(copy)
    found = compare.compare(_core.Rig(moved), truth)
    assert found["scale_error_pct"] == pytest.approx(30.0, abs=1e-6) and found["position_cm_max"] < 1e-6
    degrees = [c["orientation_deg"] for c in found["cameras"].values()]
    assert degrees[1] == pytest.approx(2.0, abs=1e-6) and max(degrees[:1] + degrees[2:]) < 1e-6
    assert found["up_deg"] == pytest.approx(np.degrees(np.arccos(turn[2, 2])), abs=1e-6)


def test_finds_a_simulated_rig_from_the_person_alone(simulated):
    take, _ = simulated
    rig, report = calibrate.calibrate(list(take.rig.cameras), take.people, take.layout, take.frame_rate, 1.7)
    s, cm, deg, up = aligned_errors(rig, take.rig)
    assert cm.max() < 1.5 and deg.max() < 0.4, (cm, deg)
    # the person leans as they balance: their standing axis is the up, within their lean
    assert report["up_from"].startswith("standing axis") and up < 8.0
    assert 0.9 < s < 1.1  # metres from the stated height, within the body proportions' spread
    assert report["reprojection_px_median"] < 5.0 and set(report["cameras"]) == {c.name for c in take.rig.cameras}


@pytest.mark.skipif(not (TRIAL_CACHE / TRIAL_DONE).is_file(), reason="the real trial is not in .cache/")
def test_the_balancing_trial_calibrates_itself_near_its_board_and_solves(tmp_path):
    # 1.72 m: the head-top keypoint's height in Pose2Sim's standing trial of the same person
    result = balancing_take.evaluate_self_calibrated(TRIAL_CACHE, tmp_path, 1.72)
    rig = result["rig"]
    assert rig["position_cm_max"] < 3.0 and rig["orientation_deg_max"] < 1.0, rig
    # the person's own shin, thigh, trunk and head stacked (with Winter's shares alone: +2.8%)
    assert abs(rig["scale_error_pct"]) < 2.0
    # the same solve with the board's rig, whose markers Pose2Sim triangulated with that rig:
    # within 0.5 cm of it once the worlds are aligned where the person is (by the camera
    # centres alone: 3.7 cm, against 2.9)
    board = balancing_take.evaluate(TRIAL_CACHE, tmp_path / "board")
    assert result["distance_cm"] < board["distance_cm"] + 0.5, (result["distance_cm"], board["distance_cm"])
    assert result["aligned_by_the_cameras"]["distance_cm"] < 4.5 and result["statuses"].get("ok", 0) >= 95
    assert calib_toml.load(tmp_path / "take" / balancing_take.SELF).cameras[0].name == "cam_01"


@pytest.mark.skipif(not (TRIAL_CACHE / TRIAL_DONE).is_file(), reason="the real trial is not in .cache/")
def test_the_camera_boxs_own_detections_calibrate_the_trials_cameras():
    from mocap.eval import edge_detector, real_trial

    videos = edge_detector.load_trial(TRIAL_CACHE)
    found, _ = edge_detector.run(edge_detector.BlazePose(), videos)
    rig = real_trial.self_calibrated(TRIAL_CACHE, real_trial.detected(found, len(videos[1])), 1.72)
    # Measured: 3.37 cm, 2.04 deg, scale +4.9% (BlazePose has no head top: Winter's shares), against
    # 2.61 cm, 0.93 deg, +0.7% from OpenPose's detections of the same videos
    assert rig["position_cm_max"] < 4.5 and rig["orientation_deg_max"] < 3.0, rig
    assert abs(rig["scale_error_pct"]) < 7.0 and rig["reprojection_px_median"] < 6.0, rig


def test_the_height_stacks_the_persons_own_segments_when_the_head_top_is_seen():
    # A long-legged person, standing: shin 0.52, thigh 0.52, trunk 0.44, mid-shoulder to head
    # top 0.28 m; their segments' shares of height are not the population's.
    shin, thigh, trunk, head = 0.52, 0.52, 0.44, 0.28
    stature = (shin + thigh + trunk + head) / (1 - world.ANKLE_HEIGHT)
    rng = np.random.default_rng(0)
    z = {"ankle": stature * world.ANKLE_HEIGHT}
    z["knee"] = z["ankle"] + shin
    z["hip"] = z["knee"] + thigh
    z["shoulder"] = z["hip"] + trunk
    kp = {f"{side}_{j}": np.array([[0.0, y, h]] * 30) + rng.normal(scale=0.002, size=(30, 3))
          for side, y in (("left", 0.1), ("right", -0.1)) for j, h in z.items()}
    kp["HeadTop"] = np.array([[0.0, 0.0, z["shoulder"] + head]] * 30)
    assert world.body_height(kp) == pytest.approx(stature, rel=0.005)
    # without a head top (COCO-17): the three against Winter's shares, off by this body's build
    del kp["HeadTop"]
    shares = (shin + thigh + trunk) / sum(world.SHARE_OF_HEIGHT.values())
    assert world.body_height(kp) == pytest.approx(shares, rel=0.005)
    assert abs(shares / stature - 1) > 0.03
    kp["HeadTop"] = np.full((30, 3), np.nan)  # a head top never seen: the same
    assert world.body_height(kp) == pytest.approx(shares, rel=0.005)


def test_a_walk_levels_the_vertical_along_its_path(shared, tmp_path):
    take_out.run(tmp_path / "take", 10.0, motion=shared / "data/mocap/cmu-daz/07_03.bvh", layout="body25b")
    take = take_folder.read_take(tmp_path / "take")
    rig, report = calibrate.calibrate(list(take.rig.cameras), take.people, take.layout, take.frame_rate, 1.7)
    _, cm, deg, up = aligned_errors(rig, take.rig)
    assert report["up_from"] == "standing axis levelled along the feet's path"
    assert up < 4.0 and cm.max() < 1.5 and deg.max() < 0.4


def test_the_command_writes_a_calib_toml_that_reads_back(simulated, tmp_path, capsys):
    _, folder = simulated
    out = tmp_path / "Calib.toml"
    assert main(["calibrate-rig", "--take", str(folder), "--height", "1.7", "--out", str(out), "--compare"]) == 0
    rig = calib_toml.load(out)
    assert [c.name for c in rig.cameras] == [c.name for c in take_folder.read_take(folder).rig.cameras]
    line = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert line["position_cm_max"] < 1.5 and line["orientation_deg_max"] < 0.4 and line["up_from"]


def _blanked(take, camera: int, keep_frames: int = 0) -> list:
    people = [list(p) for p in take.people]
    people[camera] = [p if f < keep_frames else p[:0] for f, p in enumerate(people[camera])]
    return people


@pytest.mark.parametrize("case, message", [
    ("one camera", "a rig calibration needs two or more"),
    ("a camera that saw no one", "no person detected"),
    ("a camera that saw the person on one frame", "keypoints the other cameras placed so far also see"),
    ("two cameras that never saw the person at once", "seen by two cameras on the same frame"),
    ("a height in centimetres", "give the height in metres"),
])
def test_bad_input_is_named(simulated, case, message):
    take, _ = simulated
    cams, people, height = list(take.rig.cameras), take.people, 1.7
    if case == "one camera":
        cams, people = cams[:1], people[:1]
    elif case == "a camera that saw no one":
        people = _blanked(take, 3)
    elif case == "two cameras that never saw the person at once":
        half = len(take.people[0]) // 2
        cams = cams[:2]
        people = [[p if f < half else p[:0] for f, p in enumerate(take.people[0])],
                  [p if f >= half else p[:0] for f, p in enumerate(take.people[1])]]
    elif case == "a camera that saw the person on one frame":
        people = _blanked(take, 3, keep_frames=1)
    else:
        height = 170.0
    with pytest.raises(InputError, match=message):
        calibrate.calibrate(cams, people, take.layout, take.frame_rate, height)


def test_the_command_ends_with_the_reason(tmp_path, capsys):
    assert main(["calibrate-rig", "--take", str(tmp_path), "--height", "1.7", "--out", str(tmp_path / "c.toml")]) == 2
    assert "take.toml" in capsys.readouterr().err
    live_only = ["--seconds", "5", "--every", "2"]  # a live calibration's: not silently ignored
    assert main(["calibrate-rig", "--take", str(tmp_path), "--height", "1.7", "--out", str(tmp_path / "c.toml"),
                 *live_only]) == 2
    assert "--seconds, --every: for --connect only" in capsys.readouterr().err


def _recorded(take, folder, session: bool = True):
    """The take's camera frames (and IMU batches) as a recording of the boxes' streams."""
    from mocap.recording import recorder
    from mocap.takes import messages

    path = folder / "boxes.mcap"
    with recorder.Recorder(path) as r:
        if session:
            r.attach_session(messages.write_session(take, folder / "session"))
        for arrival, type_name, payload in messages.messages(take):
            r.write([type_name.encode(), payload], arrival)
    return path


def test_a_recording_of_the_boxes_calibrates_as_its_take_does(simulated, tmp_path, capsys):
    """The boxes' KeypointFrames recorded (the intrinsics from the attached session) give the rig
    the take folder gives: the same detections (to the wire's float precision), on the same
    frames by capture time."""
    take, folder = simulated
    path = _recorded(take, tmp_path)
    assert main(["calibrate-rig", "--recording", str(path), "--height", "1.7", "--out", str(tmp_path / "r.toml"),
                 "--compare"]) == 0
    line = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert line["frames"] == take.n_frames and line["position_cm_max"] < 1.5, line
    assert main(["calibrate-rig", "--take", str(folder), "--height", "1.7", "--out", str(tmp_path / "t.toml")]) == 0
    from_recording, from_take = calib_toml.load(tmp_path / "r.toml"), calib_toml.load(tmp_path / "t.toml")
    by_name = {c.name: c for c in from_take.cameras}
    for cam in from_recording.cameras:
        assert np.allclose(cam.translation, by_name[cam.name].translation, atol=1e-3), cam.name  # 1 mm
        assert np.allclose(cam.rotation, by_name[cam.name].rotation, atol=1e-4), cam.name


def test_without_intrinsics_a_field_of_view_stands_in(simulated, tmp_path, capsys):
    take, _ = simulated
    path = _recorded(take, tmp_path, session=False)
    out = ["--height", "1.7", "--out", str(tmp_path / "fov.toml")]
    assert main(["calibrate-rig", "--recording", str(path), *out]) == 2
    assert "no intrinsics: give --intrinsics Calib.toml or --fov DEG" in capsys.readouterr().err
    cam = take.rig.cameras[0]
    fov = float(np.degrees(2 * np.arctan(cam.width / 2 / cam.fx)))  # the simulated cameras': pinholes
    assert main(["calibrate-rig", "--recording", str(path), *out, "--fov", f"{fov:.4f}"]) == 0
    rig = calib_toml.load(tmp_path / "fov.toml")
    assert abs(rig.cameras[0].fx - cam.fx) < 0.01 * cam.fx and rig.cameras[0].cx == cam.width / 2
    _, cm, deg, _ = aligned_errors(rig, take.rig)
    assert cm.max() < 2.0 and deg.max() < 0.5, (cm, deg)
    assert main(["calibrate-rig", "--recording", str(path), *out, "--fov", "200"]) == 2
    assert "give 10-170" in capsys.readouterr().err


def test_live_from_the_boxes_streams_the_rig_is_estimated_and_refined(simulated, tmp_path):
    """The boxes' streams (the take's recording replayed at twice real time) received live, the
    intrinsics from the session: an estimate written every few seconds from what came so far,
    the last from all of it, near the truth; what came is kept as a recording."""
    import threading

    from mocap.calibration.rig import live, recorded
    from mocap.demo.studio import free_ports
    from mocap.recording import replay

    take, _ = simulated
    path = _recorded(take, tmp_path)
    endpoint = f"tcp://127.0.0.1:{free_ports(1)[0]}"
    lines = []
    worker = threading.Thread(target=lambda: live.run(
        [endpoint], tmp_path / "live.mcap", tmp_path / "live.toml", 1.7,
        lambda d: recorded.intrinsics(d, None, None), 7.0, 3.0, lines.append, tmp_path / "session" / "session.json"))
    worker.start()
    try:
        replay.replay(path, endpoint, speed=2.0, restamp=True)
    finally:
        worker.join(timeout=120)
    assert not worker.is_alive()
    estimates = [line for line in lines if "out" in line]
    assert len(estimates) >= 2 and estimates[-1]["final"] and "moved_cm_max" in estimates[-1], lines
    assert estimates[0]["frames"] < estimates[-1]["frames"] >= 0.9 * take.n_frames, lines
    _, cm, deg, _ = aligned_errors(calib_toml.load(tmp_path / "live.toml"), take.rig)
    assert cm.max() < 1.5 and deg.max() < 0.4, (cm, deg)
    assert recorded.read(tmp_path / "live.mcap").cameras == sorted(c.name for c in take.rig.cameras)


def test_a_recording_without_detections_or_of_mixed_layouts_is_named(tmp_path):
    from mocap.calibration.rig import recorded
    from mocap.net import wire
    from mocap.recording import recorder

    with recorder.Recorder(tmp_path / "none.mcap") as r:
        r.write(wire.encode(wire.KeypointFrame(camera_id="cam1", capture_time_ns=1, detected=False)), 1)
    with pytest.raises(InputError, match="no camera frames with detections"):
        recorded.read(tmp_path / "none.mcap")
    with recorder.Recorder(tmp_path / "mixed.mcap") as r:
        for k, layout in enumerate(("coco17", "body25b")):
            r.write(wire.encode(wire.KeypointFrame(camera_id=f"cam{k}", capture_time_ns=1, detected=True,
                                                   keypoint_layout=layout)), 1)
    with pytest.raises(InputError, match="several keypoint layouts"):
        recorded.read(tmp_path / "mixed.mcap")
