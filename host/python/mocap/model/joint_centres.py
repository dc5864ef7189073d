"""The anatomical joint centres every skeleton agrees on: each is the origin of one bone.

A skeleton's other bone origins (the pelvis origin, the spine joints, the clavicles' inner
ends) are conventions of that skeleton that no keypoint observes: two skeletons fitted to the
same body put them centimetres apart. Outputs (joints.csv) and the comparison of solves made
with different skeletons (estimated against true calibration) use these joints.
"""

from __future__ import annotations

# Joint centre -> the bone whose origin it is.
JOINTS = {"head": "head", "left_shoulder": "upper_arm_l", "right_shoulder": "upper_arm_r",
          "left_elbow": "forearm_l", "right_elbow": "forearm_r", "left_wrist": "hand_l", "right_wrist": "hand_r",
          "left_hip": "thigh_l", "right_hip": "thigh_r", "left_knee": "shin_l", "right_knee": "shin_r",
          "left_ankle": "foot_l", "right_ankle": "foot_r"}


def bone_indices(bone_names: list[str]) -> list[int]:
    """Indices of the joint centres' bones, in JOINTS order."""
    return [bone_names.index(b) for b in JOINTS.values()]
