"""BVH writer: a pose sequence on the solver's skeleton -> a BVH motion file.

Conventions of the file written:
- Units: centimetres (what Blender's and MotionBuilder's BVH importers assume by default).
- Axes: Y up, the subject faces +Z and its left is +X in the rest pose, the usual BVH frame
  (the one `mocap.io.retarget` reads). Our world is Z up, facing +X, left +Y, so
  v_bvh = 100 * P^T v_world with P = `mocap.io.retarget.P` (a rotation, no mirroring).
- Joints: one per bone, named as the bones, OFFSETs from the skeleton's offsets (converted).
  Every bone frame is aligned with the world in the rest pose, so a joint's channel
  rotation is P^T Exp(theta_b) P and a reader that composes offsets and channels finds
  100 * P^T of the positions of `skeleton.forward_kinematics(theta)`.
- Root: OFFSET 0 0 0; its position channels hold the root's world position
  (theta[0:3] + root offset), so readers that add the offset and readers that replace it agree.
- Rotations: channels "Zrotation Xrotation Yrotation", R = Rz(z) Rx(x) Ry(y), degrees.
  Angles are exact at and near gimbal lock (x = +-90 deg) and continuous from frame to frame:
  each frame takes the Euler solution nearest the previous frame's, unwrapped (angles may
  leave [-180, 180]; they never jump by 360).
- End Site of a leaf bone: half the leaf's own offset beyond it (cosmetic, no channel).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mocap import rotations
from mocap.io._thetas import checked_thetas
from mocap.io.retarget import P

BVH_FROM_WORLD = 100.0 * P.T  # metres, Z up -> centimetres, Y up
ROTATION_CHANNELS = "Zrotation Xrotation Yrotation"
GIMBAL_COS = 1e-9  # |cos x| below this: z is held at the previous frame's, y takes the rest


def write_bvh(path: str | Path, skeleton, thetas, frame_rate: float) -> None:
    """Write poses thetas (F, pose_dim) sampled at frame_rate (Hz) to a BVH file."""
    thetas = checked_thetas(skeleton, thetas)
    if not (np.isfinite(frame_rate) and frame_rate > 0):
        raise ValueError(f"frame_rate must be positive, got {frame_rate}")
    hierarchy, order = _hierarchy(skeleton)
    frames, bones = len(thetas), skeleton.num_bones
    local = P.T @ rotations.exp(thetas[:, 3:].reshape(frames, bones, 3)) @ P
    angles = np.degrees(euler_zxy_sequence(local[:, order]))
    root = (thetas[:, :3] + skeleton.offsets[0]) @ BVH_FROM_WORLD.T
    motion = np.concatenate([root, angles.reshape(frames, -1)], axis=1)
    lines = ["HIERARCHY", *hierarchy, "MOTION", f"Frames: {frames}", f"Frame Time: {1.0 / frame_rate:.9f}"]
    lines += [" ".join(f"{v:.6f}" for v in row) for row in motion]
    Path(path).write_text("\n".join(lines) + "\n")


def euler_zxy_sequence(r: np.ndarray) -> np.ndarray:
    """(F, N, 3, 3) rotations -> (F, N, 3) radians (z, x, y), r = Rz(z) Rx(x) Ry(y), continuous in F."""
    out = np.empty(r.shape[:-1])
    previous = np.zeros(r.shape[1:-1])
    for f in range(len(r)):
        out[f] = previous = _euler_zxy(r[f], previous)
    return out


def _euler_zxy(r: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """(N, 3, 3) -> (N, 3): of the two Euler solutions, unwrapped, the one nearest previous."""
    cos_x = np.hypot(r[:, 0, 1], r[:, 1, 1])
    x = np.arctan2(r[:, 2, 1], cos_x)
    z = np.where(cos_x < GIMBAL_COS, previous[:, 0], np.arctan2(-r[:, 0, 1], r[:, 1, 1]))
    candidates = []
    for z_k, x_k in ((z, x), (z + np.pi, np.pi - x)):
        zxy = np.stack([z_k, x_k, _remaining_y(r, z_k, x_k)], axis=-1)
        candidates.append(zxy + 2 * np.pi * np.round((previous - zxy) / (2 * np.pi)))
    first, second = candidates
    use_second = np.abs(second - previous).sum(-1) < np.abs(first - previous).sum(-1)
    return np.where(use_second[:, None], second, first)


def _remaining_y(r: np.ndarray, z: np.ndarray, x: np.ndarray) -> np.ndarray:
    """y such that r = Rz(z) Rx(x) Ry(y), read from Rx(x)^T Rz(z)^T r: exact for any z at gimbal lock."""
    axis = np.eye(3)
    rest = np.swapaxes(rotations.exp(z[:, None] * axis[2]) @ rotations.exp(x[:, None] * axis[0]), -1, -2) @ r
    return np.arctan2(rest[:, 0, 2] - rest[:, 2, 0], rest[:, 0, 0] + rest[:, 2, 2])


def _hierarchy(skeleton) -> tuple[list[str], list[int]]:
    """HIERARCHY lines (depth first) and the bone order of their channels."""
    names, parents = skeleton.bone_names, skeleton.parents
    offsets = skeleton.offsets @ BVH_FROM_WORLD.T
    lines: list[str] = []
    order: list[int] = []

    def joint(b: int, pad: str) -> None:
        order.append(b)
        children = [c for c, p in enumerate(parents) if p == b]
        position = "Xposition Yposition Zposition " if b == 0 else ""
        lines.extend([f"{pad}{'ROOT' if b == 0 else 'JOINT'} {names[b]}", f"{pad}{{",
                      f"{pad}  OFFSET {_xyz(offsets[b] if b else np.zeros(3))}",
                      f"{pad}  CHANNELS {6 if b == 0 else 3} {position}{ROTATION_CHANNELS}"])
        for c in children:
            joint(c, pad + "  ")
        if not children:
            lines.extend([f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET {_xyz(offsets[b] / 2)}", f"{pad}  }}"])
        lines.append(f"{pad}}}")

    joint(0, "")
    return lines, order


def _xyz(v: np.ndarray) -> str:
    return " ".join(f"{c:.6f}" for c in v)
