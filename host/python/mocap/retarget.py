"""Map a BVH clip onto the solver's 21-bone skeleton.

Joint correspondence: each solver bone takes the first BVH joint (case-insensitive)
from its alias list below that descends from the parent bone's joint; the aliases
cover the common conventions (CMU/3ds Max "LeftHip/LeftKnee", MotionBuilder/Mixamo
"LeftUpLeg/LeftLeg", DAZ "lThigh/lShin"). A bone with no joint (e.g. toes in a file
without toe joints) sits at its parent joint's End Site and keeps the parent's rotation.

Axes: BVH files are y up, subject's left +x, facing +z; the solver is z up, left +y,
facing +x, so v_solver = P v_bvh with P the cyclic permutation below.
Units: `scale` converts file units to metres; "auto" picks the common unit (m, cm,
inch, CMU's 0.056444) that gives an adult's rest height.

Bone offsets are the BVH rest-pose differences between mapped joints, so the solver's
rest pose is the file's rest pose and each bone's world orientation is its joint's. An
intermediate joint that is skipped (e.g. "LHipJoint") folds into its parent: positions
then differ slightly from the file's where that joint rotates.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap import rotations
from mocap.bvh import Motion
from mocap.errors import InputError

P = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])

_SIDE_ALIASES = {
    "clavicle": ["{Side}Collar", "{s}Collar", "{Side}Clavicle", "{Side}Shoulder"],
    "upper_arm": ["{Side}Arm", "{Side}UpperArm", "{s}Shldr", "{Side}Shoulder"],
    "forearm": ["{Side}ForeArm", "{Side}Elbow", "{s}ForeArm", "{Side}LowerArm"],
    "hand": ["{Side}Hand", "{Side}Wrist", "{s}Hand"],
    "thigh": ["{Side}UpLeg", "{Side}Thigh", "{s}Thigh", "{Side}Hip", "{Side}UpperLeg"],
    "shin": ["{Side}Leg", "{Side}Knee", "{s}Shin", "{Side}LowerLeg", "{Side}Shin"],
    "foot": ["{Side}Foot", "{Side}Ankle", "{s}Foot"],
    "toes": ["{Side}ToeBase", "{Side}Toe", "{s}Toe", "{Side}Toes"],
}
ALIASES: dict[str, list[str]] = {
    "pelvis": ["Hips", "Hip", "Pelvis", "Root"],
    "spine_lower": ["Spine", "LowerBack", "Abdomen", "Spine1"],
    "spine_upper": ["Spine1", "Chest", "Spine2", "Chest2"],
    "neck": ["Neck", "LowerNeck", "Neck1"],
    "head": ["Head"],
}
for _side, _s, _tag in (("Left", "l", "l"), ("Right", "r", "r")):
    for _bone, _names in _SIDE_ALIASES.items():
        ALIASES[f"{_bone}_{_tag}"] = [n.format(Side=_side, s=_s) for n in _names]

# Canonical order, as in the default skeleton file (host/data/skeleton_default.json).
BONES = ["pelvis", "spine_lower", "spine_upper", "neck", "head",
         "clavicle_l", "upper_arm_l", "forearm_l", "hand_l", "clavicle_r", "upper_arm_r", "forearm_r", "hand_r",
         "thigh_l", "shin_l", "foot_l", "toes_l", "thigh_r", "shin_r", "foot_r", "toes_r"]
PARENTS = {
    "pelvis": None, "spine_lower": "pelvis", "spine_upper": "spine_lower", "neck": "spine_upper",
    "head": "neck", "clavicle_l": "spine_upper", "upper_arm_l": "clavicle_l", "forearm_l": "upper_arm_l",
    "hand_l": "forearm_l", "clavicle_r": "spine_upper", "upper_arm_r": "clavicle_r",
    "forearm_r": "upper_arm_r", "hand_r": "forearm_r", "thigh_l": "pelvis", "shin_l": "thigh_l",
    "foot_l": "shin_l", "toes_l": "foot_l", "thigh_r": "pelvis", "shin_r": "thigh_r",
    "foot_r": "shin_r", "toes_r": "foot_r",
}
UNIT_CANDIDATES = (1.0, 0.01, 0.0254, 0.056444)
REST_HEIGHT = 1.53  # metres: head joint to toes of an adult (default skeleton)


@dataclasses.dataclass
class Mapping:
    joint: list[int | None]  # per solver bone: BVH joint index, or None (End Site of parent)
    scale: float  # file units -> metres
    offsets: np.ndarray  # (21, 3) solver bone offsets, metres
    parents: list[int]


def _descends(motion: Motion, j: int, ancestor: int) -> bool:
    while j >= 0:
        if j == ancestor:
            return True
        j = motion.joints[j].parent
    return False


def map_joints(motion: Motion, scale: float | str = "auto") -> Mapping:
    lower = {j.name.lower(): i for i, j in enumerate(motion.joints)}
    joint: dict[str, int | None] = {}
    for bone in BONES:
        parent = PARENTS[bone]
        found = None
        for alias in ALIASES[bone]:
            i = lower.get(alias.lower())
            if i is None or i in joint.values():
                continue
            if parent is None or joint[parent] is None or _descends(motion, i, joint[parent]):
                found = i
                break
        if found is None and (parent is None or bone not in ("toes_l", "toes_r")):
            raise InputError(f"no BVH joint for solver bone {bone!r} (tried {ALIASES[bone]})")
        joint[bone] = found
    rest = motion.rest_positions()

    def rest_of(bone: str) -> np.ndarray:
        j = joint[bone]
        if j is not None:
            return rest[j]
        pj = motion.joints[joint[PARENTS[bone]]]
        if pj.end_site is None:
            raise InputError(f"no BVH joint or End Site for solver bone {bone!r}")
        return rest[joint[PARENTS[bone]]] + pj.end_site

    raw = np.array([rest_of(b) - (rest_of(PARENTS[b]) if PARENTS[b] else rest_of(b)) for b in BONES])
    raw = raw @ P.T
    if scale == "auto":
        heights = []
        for s in UNIT_CANDIDATES:
            pos = _rest_positions(raw * s)
            heights.append(pos[:, 2].max() - pos[:, 2].min())
        scale = UNIT_CANDIDATES[int(np.argmin([abs(h - REST_HEIGHT) for h in heights]))]
    parents = [BONES.index(PARENTS[b]) if PARENTS[b] else -1 for b in BONES]
    return Mapping([joint[b] for b in BONES], float(scale), raw * float(scale), parents)


def _rest_positions(offsets: np.ndarray) -> np.ndarray:
    pos = np.zeros_like(offsets)
    for b, name in enumerate(BONES):
        parent = PARENTS[name]
        pos[b] = offsets[b] + (pos[BONES.index(parent)] if parent else 0.0)
    return pos


def poses(motion: Motion, mapping: Mapping) -> np.ndarray:
    """(frames, 66) solver pose vectors of every frame of the clip."""
    rot, pos = motion.global_transforms()
    n = motion.num_frames
    world = np.empty((n, len(BONES), 3, 3))
    for b, j in enumerate(mapping.joint):
        world[:, b] = P @ rot[:, j] @ P.T if j is not None else world[:, mapping.parents[b]]
    theta = np.zeros((n, 3 + 3 * len(BONES)))
    theta[:, 0:3] = (pos[:, mapping.joint[0]] @ P.T) * mapping.scale - mapping.offsets[0]
    theta[:, 3:6] = rotations.log(world[:, 0])
    for b in range(1, len(BONES)):
        local = np.swapaxes(world[:, mapping.parents[b]], -1, -2) @ world[:, b]
        theta[:, 3 + 3 * b : 6 + 3 * b] = rotations.log(local)
    return theta
