"""What a take's measurements allow of each bone (mocap.eval.floors): the fit finds a bone's
orientation again from the keypoints it moves, and the sensors' own errors are those the
simulation put in."""

import dataclasses
import json

import numpy as np
import pytest

from mocap import rotations
from mocap.eval import floors
from mocap.io import retarget
from mocap.sim import detector, imu
from mocap.sim import take as sim_take

CLIP = "data/mocap/cmu-131/131_01.bvh"
UNSENSED = ["spine_lower", "neck", "clavicle_l", "clavicle_r", "hand_l", "hand_r", "toes_l", "toes_r"]


def _take(shared, detections=detector.DetectorErrors(), sensors=imu.ImuErrors(), frames=60):
    mapping, thetas, dt = retarget.load_clip(shared / CLIP, 60.0)
    skeleton = sim_take._core.Skeleton.from_bones(retarget.BONES, mapping.parents, mapping.offsets)
    config = sim_take.Config(detector=detections, imu=sensors)
    return sim_take.simulate_motion(skeleton, thetas[:frames], dt, config, np.random.default_rng(0))


def _turned(t, bone: str, turn: np.ndarray):
    """The take with `bone` turned by `turn` (its own frame) and every bone beyond it keeping
    its world orientation: what the fit is told is the truth, while the detections are not."""
    names = t.skeleton.bone_names
    j = names.index(bone)
    thetas = t.thetas.copy()
    block = 6 + 3 * (j - 1)
    thetas[:, block:block + 3] = rotations.log(rotations.exp(thetas[:, block:block + 3]) @ rotations.exp(turn))
    for c in (b for b, p in enumerate(t.skeleton.parents) if p == j):
        child = 6 + 3 * (c - 1)
        thetas[:, child:child + 3] = rotations.log(rotations.exp(-turn) @ rotations.exp(thetas[:, child:child + 3]))
    return dataclasses.replace(t, thetas=thetas)


@pytest.mark.parametrize("bone, axis", [("hand_r", [0.0, 0.0, 1.0]), ("clavicle_l", [0.0, 0.0, 1.0]),
                                        ("spine_lower", [1.0, 0.0, 0.0])])
def test_a_bone_told_wrong_is_found_again_from_the_keypoints_it_moves(shared, bone, axis):
    # Perfect detections of the clip; the fit starts 20 degrees off about an axis the keypoints
    # observe (a clavicle through the whole arm it carries) and must come back.
    t = _take(shared, detections=detector.DetectorErrors(random=False, site_offsets=False))
    turned = _turned(t, bone, np.radians(20.0) * np.array(axis))
    found = floors.keypoint_floors(turned, [bone])[bone]
    # a clavicle's twist moves no keypoint: the fit may end a little along it
    assert found["floor_deg"] == pytest.approx(20.0, abs=1.5), found
    assert floors.keypoint_floors(t, [bone])[bone]["floor_deg"] < 0.05


def test_the_true_sites_remove_the_detectors_offsets_and_only_them(shared):
    offsets_only = _take(shared, detections=detector.DetectorErrors(random=False))
    nominal = floors.keypoint_floors(offsets_only, UNSENSED)
    exact = floors.keypoint_floors(offsets_only, UNSENSED, offsets_only.detector_sites)
    assert all(exact[b]["floor_deg"] < 0.05 for b in UNSENSED), exact
    assert nominal["hand_r"]["floor_deg"] > 3.0 and nominal["toes_r"]["floor_deg"] > 3.0, nominal
    noisy = _take(shared)
    assert floors.keypoint_floors(noisy, ["hand_r"], noisy.detector_sites)["hand_r"]["floor_deg"] > 3.0


def test_a_sensors_own_error_is_what_the_simulation_put_in(shared):
    exact = floors.sensor_errors(_take(shared, sensors=imu.ImuErrors(random=False)))
    assert len(exact) == 13 and max(exact.values()) < 1e-6, exact  # mountings up to 20 degrees, references too
    spec = floors.sensor_errors(_take(shared))
    assert all(0.3 < e < 10.0 for e in spec.values()), spec


def test_the_command_writes_each_bones_floor_beside_the_solve(shared, tmp_path):
    from mocap.cli.main import main

    out = tmp_path / "floors.json"
    assert main(["eval", "--floors", "--motion", str(shared / CLIP), "--json", str(out)]) == 0
    (result,) = json.loads(out.read_text())
    assert set(result["floors"]) == set(UNSENSED) and len(result["sensors_deg"]) == 13
    assert len(result["solve_deg"]) == 21
    # the solve holds a sensed bone within a few degrees of its sensor's own error
    assert result["solve_deg"]["thigh_l"] < result["sensors_deg"]["thigh_l"] + 2.0


def test_the_command_refuses_options_the_floors_would_ignore(shared, tmp_path, capsys):
    from mocap.cli.main import main

    base = ["eval", "--floors", "--motion", str(shared / CLIP), "--json", str(tmp_path / "f.json")]
    assert main([*base, "--bend", "foot_l:x:90"]) == 2
    assert main([*base, "--site-offsets", "off", "--slip", "forearm_l:4:z:60"]) == 2
    assert "not --slip, --site-offsets off" in capsys.readouterr().err
    assert not (tmp_path / "f.json").exists()
