"""A calibration pose held at the start of a take (mocap.model.poses: a T-pose or an
N-pose), found in a video-only solve of the window.

A stretch of frames where the solve holds every limb and spine segment's direction (what
video sees, not the twist) within HELD_MAX_DEG of the pose's, the subject's facing turned
away, and turns it by less than HELD_STILL_DEG in 0.5 s (means over +-0.25 s: per-frame
solves jitter), for HELD_MIN_S or longer, is taken as the subject holding it; the window
calibration then ties those frames' joints to the pose (HELD_SIGMA), which defines the bone
frames as a suit's calibration does and pins the mountings' twist.
"""

from __future__ import annotations

import numpy as np

from mocap import _core, rotations
from mocap.calibration import imu_position
from mocap.model.poses import calibration_poses

HELD_BONES = ["spine_lower", "spine_upper", "upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r",
              "thigh_l", "thigh_r", "shin_l", "shin_r"]
HELD_MAX_DEG, HELD_STILL_DEG, HELD_MIN_S, HELD_SIGMA = 20.0, 2.0, 0.5, 0.01


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.degrees(np.arccos(np.clip(np.sum(a * b, axis=-1), -1.0, 1.0)))


def _bone_axes(skeleton: _core.Skeleton) -> tuple[list[int], np.ndarray]:
    """HELD_BONES' indices and each one's axis towards its child (bone frame)."""
    bones = [skeleton.bone_names.index(b) for b in HELD_BONES]
    children = [next(c for c, p in enumerate(skeleton.parents) if p == b) for b in bones]
    return bones, np.array([skeleton.offsets[c] / np.linalg.norm(skeleton.offsets[c]) for c in children])


def _facing_directions(skeleton: _core.Skeleton, thetas: np.ndarray, half: int) -> tuple[np.ndarray, np.ndarray]:
    """(F, bones, 3) twice: the held bones' directions, means over +-half frames; the same
    with the subject's facing (the pelvis' yaw, a median over the same frames) turned away."""
    bones, axes = _bone_axes(skeleton)
    world, yaws = [], []
    for theta in thetas:
        rot, _ = skeleton.forward_kinematics(theta)
        world.append(np.einsum("bjk,bk->bj", rot[bones], axes))
        yaws.append(np.arctan2(rot[0][1, 0], rot[0][0, 0]))  # the subject's facing, from the pelvis
    world = np.array(world)  # (F, bones, 3)
    yaws = np.unwrap(yaws)
    # Per-frame video solves jitter by degrees: the tests are on means over +-0.25 s.
    mean = np.array([world[max(0, f - half): f + half + 1].mean(axis=0) for f in range(len(world))])
    mean /= np.linalg.norm(mean, axis=-1, keepdims=True)
    yaws = np.array([np.median(yaws[max(0, f - half): f + half + 1]) for f in range(len(yaws))])
    return mean, np.einsum("fij,fbj->fbi", rotations.exp(np.stack([np.zeros_like(yaws)] * 2 + [-yaws], axis=1)),
                           mean)


def held_pose_frames(skeleton: _core.Skeleton, thetas: np.ndarray, times: np.ndarray) -> tuple[str | None, np.ndarray]:
    """The calibration pose held longest ("T" or "N", None) and its frames."""
    half = max(1, int(round(0.25 / max(float(np.median(np.diff(times))), 1e-3)))) if len(times) > 1 else 1
    mean, facing = _facing_directions(skeleton, thetas, half)
    before, after = np.roll(mean, half, axis=0), np.roll(mean, -half, axis=0)  # the means a half-window away
    still = _angle(before, after).max(axis=1) <= HELD_STILL_DEG
    still[:half] = still[-half:] = False
    bones, axes = _bone_axes(skeleton)
    best = (None, np.array([], int))
    for name, pose in calibration_poses(skeleton).items():
        target = np.einsum("bjk,bk->bj", skeleton.forward_kinematics(pose)[0][bones], axes)  # facing +x
        lo, hi = imu_position.longest_run(still & (_angle(facing, target[None]).max(axis=1) <= HELD_MAX_DEG))
        if hi <= lo:
            continue
        lo, hi = max(0, lo - half), min(len(times), hi + half)  # the frames the means held still cover
        if times[hi - 1] - times[lo] >= HELD_MIN_S and hi - lo > len(best[1]):
            best = (name, np.arange(lo, hi))
    return best


def held(frame: int, pose: np.ndarray) -> _core.HeldPose:
    """The window calibration's tie of a frame's joints to the pose."""
    h = _core.HeldPose()
    h.frame, h.theta, h.sigma = frame, pose, HELD_SIGMA
    return h
