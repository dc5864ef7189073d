"""The live demo's motion, from a registry package instead of ../shared.

Source: the Pose2Sim demo trial (PyPI pose2sim 0.4.15, BSD-3-Clause, licence kept beside
the files): `Balancing_for_IK.trc`, 21 triangulated OpenPose BODY_25B keypoints at 60 Hz,
100 frames, metres, Y up, subject's left +x, facing +z. `fetch` caches it under .cache/.

The fit: axes as retarget.P (our world is Z up, left +y, facing +x), the floor (z = 0) at the
median over frames of the lowest heel or toe marker. The default skeleton is scaled to the
markers' median distances, left and right averaged; joint markers (hips, knees, ankles,
shoulders, elbows, wrists, Neck) are bone origins; Head and Nose are sites on the head bone
at their median place in the chest frame; the heel is a site on the foot, both toe tips
sites on the toes, whose joint (the ball of the foot) lies at BALL_FRACTION of the
heel-to-toe-tip line. The foot frame is the sole's: a zero foot pose stands flat.
Each frame is then fitted by `_core.fit_to_points` (warm-started; weak anchors to bone axes
read from the markers settle what they leave open, see fit_thetas) and the motion smoothed
as retarget.load_clip does. The demo plays it forward and backward (loop_motion).

    python -m mocap.io.demo_data        # download into .cache/ (scripts/setup.sh runs it)
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from mocap import _core, rotations
from mocap.errors import InputError
from mocap.io import retarget
from mocap.io.demo_data import TRIAL, fetch
from mocap.io.trc import Trc, read_trc
from mocap.model import studio

log = logging.getLogger(__name__)

BALL_FRACTION = 0.72  # ball of the foot along heel -> toe tips (anthropometric, ~0.7-0.75)
FIT_ITERATIONS = 20  # per solve
MARKER_SIGMA, ANCHOR_SIGMA, ANCHOR_ARM = 0.01, 0.03, 0.1  # m: see fit_thetas
ANCHOR_ROUNDS = 3
DEMO_SECONDS = 60.0
EASE_S = 0.25  # the loop slows to rest over this before each turn


def world_markers(trc: Trc) -> np.ndarray:
    """(F, M, 3) markers in our world: Z up (retarget.P), floor at z = 0."""
    world = trc.markers @ retarget.P.T
    feet = [trc.names.index(s + n) for s in "LR" for n in ("Heel", "BigToe", "SmallToe")]
    lowest = np.min(np.where(np.isnan(world[:, feet, 2]), np.inf, world[:, feet, 2]), axis=1)
    world[..., 2] -= np.median(lowest[np.isfinite(lowest)])
    return world


JOINT_MARKERS = {"thigh": "Hip", "shin": "Knee", "foot": "Ankle", "upper_arm": "Shoulder", "forearm": "Elbow",
                 "hand": "Wrist"}  # bone whose origin the marker is (per side)
MARKERS = ["Neck", "Head", "Nose"] + [s + n for s in "LR"
                                     for n in [*JOINT_MARKERS.values(), "Heel", "BigToe", "SmallToe"]]


@dataclasses.dataclass(frozen=True)
class Body:
    skeleton: _core.Skeleton
    bones: list[int]  # per marker (the TRC's order): the bone it is a site of
    offsets: np.ndarray  # (M, 3) in that bone's frame, metres


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _local(axes: np.ndarray, origin: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Median over frames of points in per-frame axes (F, 3, 3: columns) at origin (F, 3)."""
    return np.nanmedian(np.einsum("fji,fj->fi", axes, points - origin), axis=0)


def _frame(x: np.ndarray, up: np.ndarray) -> np.ndarray:
    """(F, 3, 3) axes (columns x, y, z): x along x, z the part of up orthogonal to it."""
    x = _unit(x)
    z = _unit(up - np.sum(up * x, axis=-1, keepdims=True) * x)
    return np.stack([x, np.cross(z, x), z], axis=-1)


def _foot(m: dict[str, np.ndarray], side: str, mirror: np.ndarray) -> dict[str, np.ndarray]:
    """Heel, toe tips and ball in the sole's frame at the ankle: x from the heel to the toe
    tips, z up through the ankle, y left; mirrored to a left foot."""
    tip = (m[side + "BigToe"] + m[side + "SmallToe"]) / 2
    axes = _frame(tip - m[side + "Heel"], m[side + "Ankle"] - m[side + "Heel"])
    out = {n: _local(axes, m[side + "Ankle"], m[side + n]) * mirror for n in ("Heel", "BigToe", "SmallToe")}
    out["ball"] = out["Heel"] + BALL_FRACTION * ((out["BigToe"] + out["SmallToe"]) / 2 - out["Heel"])
    return out


def _trunk_axes(m: dict[str, np.ndarray], pair: str) -> np.ndarray:
    """(F, 3, 3) axes of the pelvis (pair "Hip") or chest ("Shoulder"): y from the right
    marker of the pair to the left, z from the hips' midpoint to the Neck."""
    up = m["Neck"] - (m["LHip"] + m["RHip"]) / 2
    return _frame(np.cross(m["L" + pair] - m["R" + pair], up), up)


def _offsets(m: dict[str, np.ndarray], foot: dict[str, np.ndarray], chest: np.ndarray) -> np.ndarray:
    """(21, 3) bone offsets: the default skeleton's trunk scaled to the Neck's height over the
    hips, the shoulders where they lie from the Neck, limbs and widths the median distances."""
    dist = lambda a, b: float(np.nanmedian(np.linalg.norm(m[a] - m[b], axis=-1)))  # noqa: E731
    both = lambda a, b: (dist("L" + a, "L" + b) + dist("R" + a, "R" + b)) / 2  # noqa: E731
    o, i = retarget.canonical_offsets().copy(), retarget.BONES.index
    trunk = float(np.nanmedian(np.linalg.norm(m["Neck"] - (m["LHip"] + m["RHip"]) / 2, axis=-1)))
    scale = trunk / (o[i("spine_lower"), 2] + o[i("spine_upper"), 2] + o[i("neck"), 2] - o[i("thigh_l"), 2])
    o[[i(b) for b in ("spine_lower", "spine_upper", "neck", "head", "clavicle_l", "clavicle_r", "upper_arm_l",
                      "upper_arm_r")]] *= scale
    shoulders = o[i("neck")] + _local(chest, m["Neck"], (m["LShoulder"] + m["RShoulder"]) / 2)  # from spine_upper
    for tag, sign in (("l", 1.0), ("r", -1.0)):
        o[i("thigh_" + tag)] = [0, sign * dist("LHip", "RHip") / 2, scale * o[i("thigh_" + tag), 2]]
        o[i("clavicle_" + tag)] = [shoulders[0] - o[i("upper_arm_" + tag), 0], o[i("clavicle_" + tag), 1], shoulders[2]]
        o[i("upper_arm_" + tag), 1] = sign * dist("LShoulder", "RShoulder") / 2 - o[i("clavicle_" + tag), 1]
        o[i("shin_" + tag)] = [0, 0, -both("Hip", "Knee")]
        o[i("foot_" + tag)] = [0, 0, -both("Knee", "Ankle")]
        o[i("forearm_" + tag)] = [0, sign * both("Shoulder", "Elbow"), 0]
        o[i("hand_" + tag)] = [0, sign * both("Elbow", "Wrist"), 0]
        o[i("toes_" + tag)] = foot["ball"] * [1, sign, 1]
    return o


def body_model(names: list[str], world: np.ndarray) -> Body:
    """The skeleton fitted to the markers' (F, M, 3) median geometry, and each marker's site."""
    if absent := [n for n in MARKERS if n not in names]:
        raise InputError(f"markers {absent} are missing")
    m = {n: world[:, k] for k, n in enumerate(names)}
    left, right = _foot(m, "L", np.array([1, 1, 1])), _foot(m, "R", np.array([1, -1, 1]))
    foot = {n: (left[n] + right[n]) / 2 for n in left}
    chest = _trunk_axes(m, "Shoulder")
    o = _offsets(m, foot, chest)
    sites = {"Neck": ("neck", np.zeros(3))}
    for tag, side in (("l", "L"), ("r", "R")):
        mirror = np.array([1, 1 if tag == "l" else -1, 1])
        sites |= {side + marker: (f"{bone}_{tag}", np.zeros(3)) for bone, marker in JOINT_MARKERS.items()}
        sites[side + "Heel"] = (f"foot_{tag}", foot["Heel"] * mirror)
        sites |= {side + toe: (f"toes_{tag}", (foot[toe] - foot["ball"]) * mirror) for toe in ("BigToe", "SmallToe")}
    head = o[retarget.BONES.index("head")]
    sites |= {n: ("head", _local(chest, m["Neck"], m[n]) * [1, 0, 1] - head) for n in ("Head", "Nose")}
    if extra := [n for n in names if n not in sites]:
        raise InputError(f"markers {extra} have no site on the skeleton")
    parents = [retarget.BONES.index(retarget.PARENTS[b]) if retarget.PARENTS[b] else -1 for b in retarget.BONES]
    skeleton = _core.Skeleton.from_bones(retarget.BONES, parents, o)
    return Body(skeleton, [retarget.BONES.index(sites[n][0]) for n in names], np.array([sites[n][1] for n in names]))


def marker_errors(body: Body, world: np.ndarray, thetas: np.ndarray) -> np.ndarray:
    """(F, M) distances (m) from each marker's site to the marker; NaN where it is missing."""
    sites = np.array([studio.site_positions(body.skeleton, body.bones, body.offsets, t) for t in thetas])
    return np.linalg.norm(sites - world, axis=-1)


def _swing(parent: np.ndarray, rest: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """(F, 3, 3) parent axes turned by the smallest rotation taking axis `rest` onto direction."""
    a, b = parent @ rest, _unit(direction)
    axis = np.cross(a, b)
    sin, cos = np.linalg.norm(axis, axis=-1, keepdims=True), np.sum(a * b, axis=-1, keepdims=True)
    return rotations.exp(axis * np.arctan2(sin, cos) / np.maximum(sin, 1e-12)) @ parent


def reference_axes(body: Body, names: list[str], world: np.ndarray) -> np.ndarray:
    """(F, 21, 3, 3) bone axes read from the markers alone: pelvis from the hips, chest from
    the shoulders, both upright along hips -> Neck (the lower spine halfway between them), the
    head from Head -> Nose,
    each limb segment its parent's swung onto its marker direction (the foot: ankle -> toe
    tips; the heel marker can be far off); clavicles, neck, hands and toes as their parents.
    They fix what the markers leave open."""
    m = {n: world[:, k] for k, n in enumerate(names)}
    g = np.zeros((len(world), len(retarget.BONES), 3, 3))
    i = retarget.BONES.index
    g[:, i("pelvis")] = _trunk_axes(m, "Hip")
    g[:, i("spine_upper")] = g[:, i("neck")] = _trunk_axes(m, "Shoulder")
    half = rotations.log(np.swapaxes(g[:, 0], 1, 2) @ g[:, i("spine_upper")]) / 2
    g[:, i("spine_lower")] = g[:, 0] @ rotations.exp(half)
    site = {n: body.offsets[names.index(n)] for n in ("Head", "Nose", "LBigToe", "LSmallToe")}
    g[:, i("head")] = _frame(m["Nose"] - m["Head"], g[:, i("neck"), :, 1]) @ _frame(site["Nose"] - site["Head"],
                                                                                     np.eye(3)[1]).T
    tips_rest = _unit(body.skeleton.offsets[i("toes_l")] + (site["LBigToe"] + site["LSmallToe"]) / 2)  # from the ankle
    for tag, side, sign in (("l", "L", 1.0), ("r", "R", -1.0)):
        b = {n: i(f"{n}_{tag}") for n in ("clavicle", "upper_arm", "forearm", "hand", "thigh", "shin", "foot", "toes")}
        g[:, b["clavicle"]] = g[:, i("spine_upper")]
        g[:, b["upper_arm"]] = _swing(g[:, b["clavicle"]], [0, sign, 0], m[side + "Elbow"] - m[side + "Shoulder"])
        g[:, b["forearm"]] = g[:, b["hand"]] = _swing(g[:, b["upper_arm"]], [0, sign, 0],
                                                      m[side + "Wrist"] - m[side + "Elbow"])
        g[:, b["thigh"]] = _swing(g[:, 0], [0, 0, -1], m[side + "Knee"] - m[side + "Hip"])
        g[:, b["shin"]] = _swing(g[:, b["thigh"]], [0, 0, -1], m[side + "Ankle"] - m[side + "Knee"])
        tips = (m[side + "BigToe"] + m[side + "SmallToe"]) / 2
        g[:, b["foot"]] = g[:, b["toes"]] = _swing(g[:, b["shin"]], tips_rest, tips - m[side + "Ankle"])
    return g


def _pose(skeleton: _core.Skeleton, axes: np.ndarray, hips: np.ndarray) -> np.ndarray:
    """The pose with bone axes (21, 3, 3) and the hip joints' midpoint at `hips`."""
    parents = np.array(skeleton.parents)
    local = np.concatenate([axes[:1], np.swapaxes(axes[parents[1:]], 1, 2) @ axes[1:]])
    theta = np.concatenate([np.zeros(3), rotations.log(local).ravel()])
    below = (skeleton.offsets[retarget.BONES.index("thigh_l")] + skeleton.offsets[retarget.BONES.index("thigh_r")]) / 2
    theta[:3] = hips - axes[0] @ below - skeleton.offsets[0]
    return theta


def fit_thetas(body: Body, names: list[str], world: np.ndarray) -> np.ndarray:
    """(F, 66) poses fitting the sites to the markers (weight 1 / MARKER_SIGMA^2), each frame
    from the previous one (the first from the reference axes). The markers leave some
    freedoms open (limb twists, how the spine shares a bend, the hands): weak anchors
    (1 / ANCHOR_SIGMA^2), the tips of each bone's axes (ANCHOR_ARM long) as the reference
    axes place them at the bone's origin, choose among the equally good poses. ANCHOR_ROUNDS
    solves per frame, the anchors following the origins."""
    skeleton = body.skeleton
    axes = reference_axes(body, names, world)
    bones = body.bones + [b for b in range(len(retarget.BONES)) for _ in range(3)]
    offsets = np.vstack([body.offsets, np.tile(ANCHOR_ARM * np.eye(3), (len(retarget.BONES), 1))])
    sigmas = np.repeat([MARKER_SIGMA, ANCHOR_SIGMA], [len(body.bones), 3 * len(retarget.BONES)])
    hips = (world[:, names.index("LHip")] + world[:, names.index("RHip")]) / 2
    thetas = np.empty((len(world), skeleton.pose_dim))
    theta = np.nan_to_num(_pose(skeleton, axes[0], hips[0]))  # a missing marker: that part starts at rest
    for f, markers in enumerate(world):
        for _ in range(ANCHOR_ROUNDS):
            anchors = skeleton.forward_kinematics(theta)[1][:, None] + ANCHOR_ARM * np.swapaxes(axes[f], 1, 2)
            targets = np.vstack([markers, anchors.reshape(-1, 3)])
            weights = np.isfinite(targets).all(axis=1) / sigmas**2
            ok, fitted = _core.fit_to_points(skeleton, bones, offsets, np.nan_to_num(targets), weights, theta,
                                             FIT_ITERATIONS)
            theta = fitted if ok else theta
        thetas[f] = theta
    return thetas


def fit_motion(trc: Trc, rate: float) -> tuple[_core.Skeleton, np.ndarray, float]:
    """(skeleton, (frames, 66) poses at `rate` by nearest frame, dt) fitted to a TRC's
    markers and smoothed as retarget.load_clip does; logs the marker residual."""
    world = world_markers(trc)
    body = body_model(trc.names, world)
    thetas = retarget.smooth(fit_thetas(body, trc.names, world), retarget.SMOOTH_S * trc.rate)
    errors = marker_errors(body, world, thetas)
    log.info("fit residual over %d frames: mean %.1f mm, max %.1f mm (%s)", len(thetas), 1e3 * np.nanmean(errors),
             1e3 * np.nanmax(errors), trc.names[np.nanargmax(np.nanmax(errors, axis=0))])
    t = np.arange(0.0, len(thetas) / trc.rate, 1.0 / rate)
    return body.skeleton, thetas[np.minimum(np.round(t * trc.rate).astype(int), len(thetas) - 1)], 1.0 / rate


def interpolate(thetas: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Poses at fractional frames: the root position linearly, each joint rotation on SO(3)."""
    lo = np.minimum(np.floor(at).astype(int), len(thetas) - 2)
    frac = (at - lo)[:, None]
    a, b = thetas[lo], thetas[lo + 1]
    ra, rb = (rotations.exp(x[:, 3:].reshape(len(at), -1, 3)) for x in (a, b))
    step = rotations.log(np.swapaxes(ra, -1, -2) @ rb) * frac[..., None]
    out = a + frac * (b - a)
    out[:, 3:] = rotations.log(ra @ rotations.exp(step)).reshape(len(at), -1)
    return out


def loop_motion(thetas: np.ndarray, seconds: float, dt: float, ease_s: float = EASE_S) -> np.ndarray:
    """At least `seconds` of the motion played forward, backward, forward... Each pass slows
    to rest over ease_s before it turns (a sine-squared ramp of the playback speed), so the
    poses and their velocity are continuous at the turns: no jump for the cameras, no
    acceleration spike for the IMUs."""
    if len(thetas) < 2:
        return np.repeat(thetas, max(1, int(np.ceil(seconds / dt))), axis=0)
    ease = max(1, round(ease_s / dt))
    speed = np.ones(len(thetas) - 1 + ease)  # frames of the clip per output frame
    ramp = np.sin(0.5 * np.pi * (np.arange(ease) + 0.5) / ease) ** 2
    speed[:ease], speed[-ease:] = np.minimum(ramp, speed[:ease]), np.minimum(ramp[::-1], speed[-ease:])
    at = np.concatenate([[0.0], np.cumsum(speed)]) * (len(thetas) - 1) / speed.sum()
    forward = interpolate(thetas, at)
    passes = int(np.ceil(seconds / dt / (len(forward) - 1)))
    out = [forward] + [(forward[::-1] if k % 2 else forward)[1:] for k in range(1, passes + 1)]
    return np.concatenate(out)[: max(len(forward), int(np.ceil(seconds / dt)))]


def after_held_pose(thetas: np.ndarray, pose: np.ndarray, dt: float, hold_s: float = 1.0,
                    blend_s: float = 0.5) -> np.ndarray:
    """The motion after a calibration pose: `pose` (its joints; root where the motion starts,
    facing its way) held for hold_s, then blended into the motion's first pose over blend_s."""
    hold, blend = round(hold_s / dt), round(blend_s / dt)
    prefix = np.tile(pose, (hold + blend, 1))
    prefix[:, :6] = thetas[0, :6]
    w = np.linspace(0.0, 1.0, blend)[:, None]
    prefix[hold:, 6:] = (1 - w) * prefix[hold:, 6:] + w * thetas[0, 6:]
    return np.vstack([prefix, thetas])


def load_motion(rate: float = 60.0, seconds: float = DEMO_SECONDS) -> tuple[_core.Skeleton, np.ndarray, float]:
    """The demo's (skeleton, poses, dt): the Balancing trial, fetched if needed, fitted and
    looped (loop_motion) to `seconds`."""
    skeleton, thetas, dt = fit_motion(read_trc(fetch() / TRIAL), rate)
    return skeleton, loop_motion(thetas, seconds, dt), dt
