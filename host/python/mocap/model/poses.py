"""The calibration poses suits ask for at the start of a take, as poses of a skeleton: a
T-pose (the rest pose: arms out) and an N-pose (standing, arms hanging). The simulator plays
them (`mocap simulate --calibration-pose`), the window calibration recognises them."""

from __future__ import annotations

import numpy as np

from mocap import _core


def calibration_poses(skeleton: _core.Skeleton) -> dict[str, np.ndarray]:
    """The poses recognised: "T" (the rest pose) and "N" (the upper arms turned down)."""
    n_pose = np.zeros(skeleton.pose_dim)
    n_pose[3 + 3 * skeleton.bone_names.index("upper_arm_l")] = -np.pi / 2
    n_pose[3 + 3 * skeleton.bone_names.index("upper_arm_r")] = np.pi / 2
    return {"T": np.zeros(skeleton.pose_dim), "N": n_pose}
