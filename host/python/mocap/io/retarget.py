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

Rest poses differ between files (legs splayed or straight, T- or A-pose), so rotations
are re-expressed against one canonical rest pose, that of the default skeleton
(host/data/skeleton_default.json): each bone gets a constant correction C_b turning its
canonical rest frame onto the file's. Pelvis and upper spine: the left-right axis between
their paired children (hips, clavicles) exactly, then the chain child (spine, neck) as
well as it can (TRIAD); a bone with one child: the minimal rotation of that child's
direction; rest vectors under 1 cm are ignored; a bone left with nothing keeps its
parent's correction. Then
  G_b = P R_b P^T C_b  (world orientation),   t_c = C_parent^T (P o_c)  (offsets),
so joint positions are exactly the file's and a zero pose is the canonical T-pose.
An intermediate joint that is skipped (e.g. "LHipJoint") folds into its parent: positions
then differ slightly from the file's where that joint rotates.
"""

from __future__ import annotations

import dataclasses
import functools
import json

import numpy as np

from mocap import paths, rotations
from mocap.errors import InputError
from mocap.io import bvh
from mocap.io.bvh import Motion

P = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])

_SIDE_ALIASES = {
    "clavicle": ["{Side}Collar", "{s}Collar", "{Side}Clavicle", "{Side}Shoulder"],
    "upper_arm": ["{Side}Arm", "{Side}UpperArm", "{s}Shldr", "{Side}Shoulder"],
    "forearm": ["{Side}ForeArm", "{Side}Elbow", "{s}ForeArm", "{Side}LowerArm"],
    "hand": ["{Side}Hand", "{s}Hand", "{Side}Wrist"],  # the distal joint: CMU "lhand", not its "LeftWrist"
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
    offsets: np.ndarray  # (21, 3) solver bone offsets in the canonical bone frames, metres
    parents: list[int]
    corrections: np.ndarray  # (21, 3, 3) C_b: canonical bone frame -> the file's rest frame


@functools.cache
def canonical_offsets() -> np.ndarray:
    """(21, 3) offsets of the default skeleton, whose rest pose is the canonical one."""
    bones = json.loads(paths.DEFAULT_SKELETON.read_text())["bones"]
    by_name = {b["name"]: np.asarray(b["offset"], dtype=float) for b in bones}
    return np.array([by_name[b] for b in BONES])


def _minimal_rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation turning direction a onto direction b."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    axis = np.cross(a, b)
    s, c = np.linalg.norm(axis), float(np.dot(a, b))
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        perp = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
        return rotations.exp(np.pi * perp / np.linalg.norm(perp))
    return rotations.exp(axis / s * np.arctan2(s, c))


# Bones with several children: the child that continues the chain, and the left/right pair
# whose difference gives the lateral axis.
CHAIN = {"pelvis": "spine_lower", "spine_upper": "neck"}
LATERAL = {"pelvis": ("thigh_l", "thigh_r"), "spine_upper": ("clavicle_l", "clavicle_r")}
MIN_LENGTH = 0.01  # m: shorter rest vectors (e.g. a spine joint at the hip centre) say nothing


def _triad(a1: np.ndarray, a2: np.ndarray, b1: np.ndarray, b2: np.ndarray) -> np.ndarray:
    """Rotation turning a1 exactly onto b1 and a2 as close as it can onto b2."""
    def frame(u, v):
        e1 = u / np.linalg.norm(u)
        e2 = np.cross(u, v)
        e2 /= np.linalg.norm(e2)
        return np.stack([e1, e2, np.cross(e1, e2)], axis=1)
    return frame(b1, b2) @ frame(a1, a2).T


def _correction(b: int, canonical: np.ndarray, source: np.ndarray, parents: list[int]) -> np.ndarray | None:
    """C_b from the bone's children (None: keep the parent's)."""
    name = BONES[b]
    pairs = []  # (canonical vector, source vector), most trusted first
    if name in LATERAL:
        left, right = (BONES.index(n) for n in LATERAL[name])
        pairs.append((canonical[left] - canonical[right], source[left] - source[right]))
    kids = [c for c in range(len(BONES)) if parents[c] == b]
    chain = BONES.index(CHAIN[name]) if name in CHAIN else (kids[0] if len(kids) == 1 else None)
    if chain is not None:
        pairs.append((canonical[chain], source[chain]))
    pairs = [(a, s) for a, s in pairs if np.linalg.norm(a) > MIN_LENGTH and np.linalg.norm(s) > MIN_LENGTH]
    if not pairs:
        return None
    if len(pairs) == 1:
        return _minimal_rotation(*pairs[0])
    (a1, b1), (a2, b2) = pairs
    return _triad(a1, a2, b1, b2)


def _corrections(source: np.ndarray, parents: list[int]) -> np.ndarray:
    canonical = canonical_offsets()
    out = np.empty((len(BONES), 3, 3))
    for b in range(len(BONES)):
        c = _correction(b, canonical, source, parents)
        out[b] = c if c is not None else (out[parents[b]] if parents[b] >= 0 else np.eye(3))
    return out


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
    source = raw * float(scale)
    corrections = _corrections(source, parents)
    offsets = np.array([corrections[parents[b]].T @ source[b] if b else source[b] for b in range(len(BONES))])
    return Mapping([joint[b] for b in BONES], float(scale), offsets, parents, corrections)


def _rest_positions(offsets: np.ndarray) -> np.ndarray:
    pos = np.zeros_like(offsets)
    for b, name in enumerate(BONES):
        parent = PARENTS[name]
        pos[b] = offsets[b] + (pos[BONES.index(parent)] if parent else 0.0)
    return pos


# Motion smoothing on load: a zero-phase Gaussian of 17 ms (-3 dB at 8 Hz, above the band
# of human movement; gait analysis filters at 6 Hz). Some clips (the DAZ conversions of
# CMU) carry frame-to-frame jitter whose second difference reads as 20-30 m/s^2 at a
# walking head, where the clean clips show 2-3; the simulated accelerometers and the
# wobble that grows with acceleration must see motion, not that jitter.
SMOOTH_S = 1.0 / 60.0


def load_clip(path, rate: float, smooth_s: float = SMOOTH_S) -> tuple[Mapping, np.ndarray, float]:
    """A BVH clip as (mapping, (frames, 66) canonical poses at `rate` by nearest frame, dt),
    smoothed first (smooth: Gaussian sigma in seconds, 0 for none)."""
    motion = bvh.load(path)
    mapping = map_joints(motion)
    thetas = smooth(poses(motion, mapping), smooth_s / motion.frame_time)
    t = np.arange(0.0, motion.num_frames * motion.frame_time, 1.0 / rate)
    return mapping, thetas[np.minimum(np.round(t / motion.frame_time).astype(int), motion.num_frames - 1)], 1.0 / rate


def smooth(thetas: np.ndarray, sigma_frames: float) -> np.ndarray:
    """Zero-phase Gaussian smoothing of (F, 3 + 3B) poses: the root position per axis, each
    rotation as a sign-aligned quaternion, renormalised. Ends are padded by repetition."""
    if sigma_frames <= 0 or len(thetas) < 2:
        return thetas.copy()
    half = int(np.ceil(3 * sigma_frames))
    kernel = np.exp(-0.5 * (np.arange(-half, half + 1) / sigma_frames) ** 2)
    kernel /= kernel.sum()

    def convolve(x: np.ndarray) -> np.ndarray:  # along axis 0
        padded = np.concatenate([np.repeat(x[:1], half, 0), x, np.repeat(x[-1:], half, 0)])
        return sum(w * padded[i : i + len(x)] for i, w in enumerate(kernel))

    out = np.empty_like(thetas)
    out[:, :3] = convolve(thetas[:, :3])
    rot = thetas[:, 3:].reshape(len(thetas), -1, 3)
    q = rotations.quaternion_from_matrix(rotations.exp(rot))  # (F, B, 4)
    flip = np.cumprod(np.where((q[1:] * q[:-1]).sum(-1) < 0, -1.0, 1.0), axis=0)
    q[1:] *= flip[..., None]
    q = convolve(q)
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    out[:, 3:] = rotations.log(rotations.matrix_from_quaternion(q)).reshape(len(thetas), -1)
    return out


def poses(motion: Motion, mapping: Mapping) -> np.ndarray:
    """(frames, 66) solver pose vectors of every frame of the clip."""
    rot, pos = motion.global_transforms()
    n = motion.num_frames
    source = np.empty((n, len(BONES), 3, 3))  # the file's joint orientations, solver axes
    for b, j in enumerate(mapping.joint):
        source[:, b] = P @ rot[:, j] @ P.T if j is not None else source[:, mapping.parents[b]]
    world = source @ mapping.corrections  # canonical bone orientations
    theta = np.zeros((n, 3 + 3 * len(BONES)))
    theta[:, 0:3] = (pos[:, mapping.joint[0]] @ P.T) * mapping.scale - mapping.offsets[0]
    theta[:, 3:6] = rotations.log(world[:, 0])
    for b in range(1, len(BONES)):
        local = np.swapaxes(world[:, mapping.parents[b]], -1, -2) @ world[:, b]
        theta[:, 3 + 3 * b : 6 + 3 * b] = rotations.log(local)
    return theta
