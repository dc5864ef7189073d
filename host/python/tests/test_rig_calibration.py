"""`mocap calibrate-rig`: the cameras' poses from the person in view, no board — on a
simulated take (every camera's pose known) and on Pose2Sim's real Balancing trial (its own
Qualisys board calibration as the reference); bad input ends with the reason."""

import json

import numpy as np
import pytest

from mocap import _core, rotations
from mocap.calibration.rig import calibrate, compare
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
    assert abs(rig["scale_error_pct"]) < 4.0
    # with the board's rig 2.9 cm: Pose2Sim's markers were triangulated with it
    assert result["distance_cm"] < 4.5 and result["statuses"].get("ok", 0) >= 95
    assert calib_toml.load(tmp_path / "take" / balancing_take.SELF).cameras[0].name == "cam_01"


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
