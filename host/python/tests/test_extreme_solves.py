"""The fused solve on takes beyond the clips (mocap.sim.extremes): a sensor's orientation wins
over the pose prior on joints bent past the training motion, and a sensor that slips on its
segment is named and left out within a second."""

import pytest

from mocap.eval import simulated
from mocap.sim import extremes
from mocap.sim import take as sim_take

CLIP = "data/mocap/cmu-131/131_01.bvh"  # a walk of the test split: the prior never saw its performer


def _evaluate(shared, bends=(), slips=()):
    config = sim_take.Config(bends=tuple(map(extremes.Bend.parse, bends)), slips=tuple(map(extremes.Slip.parse, slips)))
    return simulated.evaluate(shared / CLIP, config, [], seed=0, calibration="oracle")


def test_feet_bent_far_past_the_training_motion_follow_their_sensors(shared):
    # The prior, trained on walks, pulls a foot bent 90 degrees back; with a robust loss on
    # E_R the sensor's pull is capped and the foot came out 83 degrees off (measured).
    r = _evaluate(shared, bends=["foot_l,foot_r:x:90"])
    for bone in ("foot_l", "foot_r"):
        assert r["extremes"][f"bent {bone}"]["mean_deg"] < 10.0, r["extremes"]
    assert r["distrusted"] == {}, "the keypoints agree with the bent feet's sensors"


@pytest.mark.parametrize("slip, bone_deg", [("shin_r:4:x:90", 12.0), ("upper_arm_r:4:x:45", 15.0)])
def test_a_slipped_sensor_is_named_within_a_second_and_left_out(shared, slip, bone_deg):
    sensor = slip.split(":")[0]
    r = _evaluate(shared, slips=[slip])
    assert set(r["distrusted"]) == {sensor}, r["distrusted"]
    assert 4.0 < r["distrusted"][sensor]["first_s"] < 5.0
    # left out to the take's end (8.3 s): it never agrees with its bone again
    assert r["distrusted"][sensor]["seconds"] > 3.5
    (errors,) = r["extremes"].values()
    assert errors["mean_deg"] < bone_deg, errors  # the slip itself: 45-90 degrees
