"""glTF 2.0 writer (pygltflib): a BVH motion -> a binary glTF (.glb) with a skinned skeleton
and its animation, as animation tools (Blender, Unity, Unreal, three.js) import it.

Conventions of the file written:
- Axes: the BVH's, which are glTF's for the BVH files the project writes (mocap.io.bvh_export:
  Y up, the subject facing +Z, its left +X); units: the BVH's times `scale` (its cm -> m).
- Nodes: one per BVH joint, named as it, its translation the joint's offset and its rotation
  the channels' (identity at rest), children as in the hierarchy; the scene's roots are the
  root joint and the mesh's node.
- Skin: every joint; inverse bind matrices of the rest pose (all channels zero). Mesh: a box
  per bone segment (a joint to each child, and to its End Site), 3 cm thick, every vertex
  weighted 1 to the joint whose segment it is: the skeleton drawn as a body.
- Animation "take": a rotation channel per joint and a translation channel per joint with
  position channels (the root), one keyframe per BVH frame at k * frame_time, LINEAR
  (quaternions kept in one hemisphere from frame to frame: no long way round).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib as gl

from mocap import rotations
from mocap.io.bvh import Motion

BOX_HALF_WIDTH_M = 0.015
FLOAT, USHORT = gl.FLOAT, gl.UNSIGNED_SHORT


class _Buffer:
    """One binary buffer of the file, its views and accessors appended as they come."""

    def __init__(self, gltf: gl.GLTF2) -> None:
        self.gltf, self.data = gltf, bytearray()

    def add(self, array: np.ndarray, kind: str, component: int, target: int | None = None,
            bounds: bool = False) -> int:
        """An accessor over `array` (rows of `kind`: SCALAR, VEC3, VEC4, MAT4); its index."""
        raw = np.ascontiguousarray(array, dtype=np.float32 if component == FLOAT else np.uint16).tobytes()
        self.data += b"\0" * (-len(self.data) % 4)
        self.gltf.bufferViews.append(gl.BufferView(buffer=0, byteOffset=len(self.data), byteLength=len(raw),
                                                   target=target))
        self.data += raw
        rows = array.reshape(len(array), -1)
        accessor = gl.Accessor(bufferView=len(self.gltf.bufferViews) - 1, componentType=component, count=len(array),
                               type=kind)
        if bounds:
            accessor.min, accessor.max = rows.min(axis=0).tolist(), rows.max(axis=0).tolist()
        self.gltf.accessors.append(accessor)
        return len(self.gltf.accessors) - 1


def _continuous(q: np.ndarray) -> np.ndarray:
    """(frames, 4) quaternions with each one's sign chosen nearest the previous frame's."""
    q = q.copy()
    for k in range(1, len(q)):
        if np.dot(q[k], q[k - 1]) < 0:
            q[k] = -q[k]
    return q


def _segments(motion: Motion, rest: np.ndarray) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """(joint, start, end) in the rest pose of each bone segment drawn: a joint to each
    child, and to its End Site."""
    out = [(j.parent, rest[j.parent], rest[i]) for i, j in enumerate(motion.joints) if j.parent >= 0]
    out += [(i, rest[i], rest[i] + j.end_site) for i, j in enumerate(motion.joints) if j.end_site is not None]
    return [s for s in out if np.linalg.norm(s[2] - s[1]) > 1e-9]


def _box(start: np.ndarray, end: np.ndarray, half: float) -> tuple[np.ndarray, np.ndarray]:
    """The 8 corners and 12 triangles (corner indices, outward) of a box from start to end."""
    axis = (end - start) / np.linalg.norm(end - start)
    side = np.cross(axis, [0.0, 1.0, 0.0] if abs(axis[1]) < 0.9 else [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    up = np.cross(axis, side)
    corners = np.array([p + half * (a * side + b * up) for p in (start, end) for a in (-1, 1) for b in (-1, 1)])
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return corners, np.array([t for a, b, c, d in faces for t in ((a, b, c), (a, c, d))])


def _add_mesh(gltf: gl.GLTF2, buffer: _Buffer, motion: Motion, rest: np.ndarray, scale: float) -> None:
    """The skinned boxes of the bone segments, on a node of their own with the skin."""
    positions, joints, triangles = [], [], []
    for joint, start, end in _segments(motion, rest):
        corners, faces = _box(scale * start, scale * end, BOX_HALF_WIDTH_M)
        triangles.append(faces + 8 * len(positions))
        positions.append(corners)
        joints.append(np.tile([joint, 0, 0, 0], (8, 1)))
    positions, joints = np.concatenate(positions), np.concatenate(joints)
    weights = np.tile([1.0, 0.0, 0.0, 0.0], (len(positions), 1))
    attributes = gl.Attributes(POSITION=buffer.add(positions, gl.VEC3, FLOAT, gl.ARRAY_BUFFER, bounds=True),
                               JOINTS_0=buffer.add(joints, gl.VEC4, USHORT, gl.ARRAY_BUFFER),
                               WEIGHTS_0=buffer.add(weights, gl.VEC4, FLOAT, gl.ARRAY_BUFFER))
    indices = buffer.add(np.concatenate(triangles).reshape(-1), gl.SCALAR, USHORT, gl.ELEMENT_ARRAY_BUFFER)
    gltf.meshes.append(gl.Mesh(name="body", primitives=[gl.Primitive(attributes=attributes, indices=indices)]))
    inverse_bind = np.tile(np.eye(4), (len(rest), 1, 1))
    inverse_bind[:, :3, 3] = -scale * rest
    gltf.skins.append(gl.Skin(name="skeleton", joints=list(range(len(rest))), skeleton=0,
                              inverseBindMatrices=buffer.add(inverse_bind.transpose(0, 2, 1), gl.MAT4, FLOAT)))
    gltf.nodes.append(gl.Node(name="body", mesh=0, skin=0))


def _add_animation(gltf: gl.GLTF2, buffer: _Buffer, motion: Motion, scale: float) -> None:
    """One rotation channel per joint, a translation channel per joint with position channels."""
    local_r, local_t = motion.local_transforms()
    times = buffer.add(np.arange(motion.num_frames) * motion.frame_time, gl.SCALAR, FLOAT, bounds=True)
    animation = gl.Animation(name="take")
    for i, joint in enumerate(motion.joints):
        paths = [("rotation", _continuous(rotations.quaternion_from_matrix(local_r[:, i]))[:, [1, 2, 3, 0]])]
        if any(c.lower().endswith("position") for c in joint.channels):
            paths.append(("translation", scale * local_t[:, i]))
        for path, values in paths:
            output = buffer.add(values, gl.VEC4 if path == "rotation" else gl.VEC3, FLOAT)
            animation.samplers.append(gl.AnimationSampler(input=times, output=output, interpolation="LINEAR"))
            animation.channels.append(gl.AnimationChannel(sampler=len(animation.samplers) - 1,
                                                          target=gl.AnimationChannelTarget(node=i, path=path)))
    gltf.animations.append(animation)


def write_glb(path: str | Path, motion: Motion, scale: float = 0.01) -> None:
    """The motion as a binary glTF file (see the module docstring); scale: file units -> metres."""
    if not (np.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be positive, got {scale}")
    gltf = gl.GLTF2(asset=gl.Asset(generator="mocap export", version="2.0"))
    rest = motion.rest_positions()
    for i, joint in enumerate(motion.joints):
        children = [k for k, c in enumerate(motion.joints) if c.parent == i]
        gltf.nodes.append(gl.Node(name=joint.name, translation=(scale * joint.offset).tolist(),
                                  children=children or None))
    buffer = _Buffer(gltf)
    _add_mesh(gltf, buffer, motion, rest, scale)
    _add_animation(gltf, buffer, motion, scale)
    roots = [i for i, j in enumerate(motion.joints) if j.parent < 0]
    gltf.scenes.append(gl.Scene(name="take", nodes=[*roots, len(gltf.nodes) - 1]))
    gltf.scene = 0
    gltf.buffers.append(gl.Buffer(byteLength=len(buffer.data)))
    gltf.set_binary_blob(bytes(buffer.data))
    gltf.save_binary(str(path))
