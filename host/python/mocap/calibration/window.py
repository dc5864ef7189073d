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
   its accelerations turn with the heading alone. A heading still further from its
   accelerometer's than that allows is held there, or the sensor left out (`headings`).
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

from mocap import _core, paths, rotations
from mocap.calibration import headings, imu_position, plausible
from mocap.calibration import imus as imu_calibration
from mocap.calibration import skeleton as skeleton_estimate
from mocap.calibration.calibration_input import CalibrationInput
from mocap.calibration.held_pose import held, held_pose_frames
from mocap.calibration.readings import ImuReadings
from mocap.errors import InputError
from mocap.model import prior
from mocap.model.poses import calibration_poses
from mocap.model.solver import Solver

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
class Calibration:
    skeleton: _core.Skeleton
    layout: _core.KeypointLayout
    imus: list  # _core.ImuSite with the estimated mount, reference and offset
    skeleton_start: skeleton_estimate.SkeletonEstimate  # step 1
    report: dict
    window_frames: np.ndarray  # (W,) the frames of the joint solve
    window_thetas: np.ndarray  # (W, 66) their poses, with the estimated skeleton
    site_directions: np.ndarray  # (3 x keypoints, kept): the sites' directions step 4b observed
    floor_height: float = float("nan")  # m, world z: the floor under the window's poses (E_G's; NaN: unknown)


def solver_options(options: _core.SolverOptions | None = None) -> _core.SolverOptions:
    """Solver options for a solve with a window calibration: heading tracking on."""
    options = options or _core.SolverOptions()
    options.heading_time_constant = HEADING_TIME_CONSTANT_S
    return options


def _video_motion() -> _core.SolverOptions:
    """The calibration's own solves, the IMUs fitted to them: no E_M, E_P's plain loss (held poses were tuned on it)."""
    options = _core.SolverOptions()
    options.motion.enabled, options.video_only_position_loss_scale = False, 1.0
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


def group_indices(skeleton: _core.Skeleton, groups: dict[str, list[str]]) -> list[int]:
    """Per bone: the index of its group in `groups`, -1 for none."""
    out = [-1] * skeleton.num_bones
    for g, bones in enumerate(groups.values()):
        for b in bones:
            out[skeleton.bone_names.index(b)] = g
    return out


def estimate(rig: _core.Rig, data: CalibrationInput, seconds: float = SECONDS, step: int = STEP,
             site_std: float = SITE_OBSERVABLE_STD, use_held_pose: bool = True,
             first_frame: int = 0, quick: bool = False) -> Calibration:
    """The calibration from a take's frames, over the `seconds` from first_frame on; the
    keypoint sites are estimated (step 4b) along the directions known within site_std (m; 0:
    the layout's sites kept) when there are IMUs to pin the bones' orientations. quick: one
    window solve (no accelerometer headings, no sites), about half the time: a first
    calibration for a live session, while the full one runs."""
    if first_frame:
        f = first_frame
        c = estimate(rig, data.tail(f), seconds, step, site_std, use_held_pose, quick=quick)
        c.window_frames = c.window_frames + f
        c.report["window_start_s"] = float(data.times[f] - data.times[0])
        return c
    detections, times, readings = data.detections, data.times, data.readings
    window = max(int(np.searchsorted(times, times[0] + seconds)), 1)
    w = _Window(rig, detections[:window], times[:window], readings, step)
    start = _start(w, data.layout)
    pose_name, held_frames = held_pose_frames(start.skeleton, start.thetas, w.times) if use_held_pose else (None, [])
    held_set = set(np.asarray(held_frames).tolist())
    frames, starts, used = _joint_frames(w, len(start.sites), start.thetas, held_set)
    if not frames:
        raise InputError(f"no frame of the first {seconds:g} s is seen by two cameras: nothing to calibrate from")
    options = _options(start.skeleton, [j for j, f in enumerate(used) if f in held_set],
                       calibration_poses(start.skeleton).get(pose_name))
    dense = len(used) * step >= DENSE * window
    estimate_sites = site_std > 0 and readings is not None and len(readings.names) > 0 and not quick
    solved = _solve_window(w, start, frames, starts, options, dense, quick, site_std if estimate_sites else 0.0)
    report = _report(w, start, solved, len(frames), quick, estimate_sites, pose_name, len(options.held_poses))
    imus = [s for s in solved.result.imus if s.name not in solved.left_out]
    report["imu_positions"] = _place_imus(solved.result.skeleton, rig, solved.layout, imus, w.detections, w.times,
                                          readings, dense)
    floor = _core.floor_height(solved.result.skeleton, np.array(solved.thetas))  # ground.h's definition
    report["floor_height_m"] = floor if np.isfinite(floor) else None
    return Calibration(solved.result.skeleton, solved.layout, imus, start.estimate, report, np.array(used),
                       np.array(solved.thetas), solved.directions, floor)


@dataclasses.dataclass
class _Window:
    """The window's inputs: detections (W, C, K, 3) at times (W,), the readings (all frames)."""
    rig: _core.Rig
    detections: np.ndarray
    times: np.ndarray
    readings: ImuReadings | None
    step: int


@dataclasses.dataclass
class _Start:
    """Steps 1-3: the skeleton from triangulated keypoints, the window solved from video with
    it, and each IMU's mounting and heading against that solve."""
    estimate: skeleton_estimate.SkeletonEstimate
    skeleton: _core.Skeleton
    layout: _core.KeypointLayout
    thetas: np.ndarray  # (W, 66)
    sites: list  # _core.ImuSite per sensor
    residuals_deg: list[float]  # step 3's, per sensor (NaN: too few readings)


def _start(w: _Window, layout_name: str) -> _Start:
    estimate = skeleton_estimate.estimate(w.rig, w.detections, layout_name)
    skel = estimate.skeleton
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / f"{layout_name}.json"), skel).scaled_to(skel)
    thetas, _ = solve_frames(Solver(skel, w.rig, layout, [], options=_video_motion()), w.detections, w.times, None)
    sites, first = [], []
    bone_world = np.array([skel.forward_kinematics(t)[0] for t in thetas])
    for i, name in enumerate(w.readings.names if w.readings else []):
        site = _core.ImuSite()
        site.name, site.bone = name, w.readings.bones[i]
        first.append(_mounting(site, skel, bone_world, w.readings.quaternions[:len(w.times), i]))
        sites.append(site)
    return _Start(estimate, skel, layout, thetas, sites, first)


def _mounting(site: _core.ImuSite, skel: _core.Skeleton, bone_world: np.ndarray, q: np.ndarray) -> float:
    """Step 3 for one IMU: sets the site's mount and reference; its residual (deg; NaN: fewer
    than 10 readings, the site left as it is)."""
    seen = np.isfinite(q).all(axis=1)
    if seen.sum() < 10:
        return float("nan")
    c = imu_calibration.calibrate(site.name, skel.bone_names[site.bone], bone_world[seen, site.bone],
                                  rotations.matrix_from_quaternion(q[seen]))
    site.mount, site.reference = c.mount, rotations.exp(np.array([0.0, 0.0, c.heading_rad]))
    return c.residual_deg


def _joint_frames(w: _Window, n_sites: int, thetas: np.ndarray, held_frames: set[int]) -> tuple[list, list, list]:
    """The frames of the joint solve: every `step`-th seen by two cameras or more, and every
    held one so seen; (the solver's frames, their starting poses, their indices)."""
    frames, starts, used = [], [], []
    seen_by = (w.detections[:, :, :, 2] > 0).any(axis=2).sum(axis=1)  # cameras per frame
    seen = np.flatnonzero(seen_by >= 2)  # frames between detections add nothing
    for f in sorted(set(seen[::w.step].tolist()) | (held_frames & set(seen.tolist()))):  # every held frame
        cams = [c for c in range(w.detections.shape[1]) if (w.detections[f, c, :, 2] > 0).any()]
        q = w.readings.quaternions[f] if w.readings else np.zeros((0, 4))
        frames.append((float(w.times[f]), cams, w.detections[f, cams], list(range(n_sites)), q,
                       np.full((n_sites, 3), np.nan)))
        starts.append(thetas[f])
        used.append(f)
    return frames, starts, used


def _options(skel: _core.Skeleton, held_frames: list[int], pose: np.ndarray | None) -> _core.CalibrationOptions:
    """Step 4's options: the length and shift groups, the joint convention, the held pose's
    ties (held_frames: indices into the joint solve's frames)."""
    options = _core.CalibrationOptions()
    options.scale_group = group_indices(skel, LENGTH_GROUPS)
    options.shift_group = group_indices(skel, {g: bones for g, (bones, _) in SHIFT_GROUPS.items()})
    options.shift_sigmas = [np.array(sigma) for _, sigma in SHIFT_GROUPS.values()]
    options.estimate_sites = False
    options.scale_sigma = SCALE_SIGMA
    options.joint_sigmas = [np.array(JOINT_SIGMAS.get(b, (0.0, 0.0, 0.0))) for b in skel.bone_names]
    options.held_poses = [held(j, pose) for j in held_frames]
    return options


@dataclasses.dataclass
class _Solved:
    result: object  # _core.calibrate_window's, step 4 (with the accelerometer's headings when found)
    accelerometer: dict[str, tuple[float, float]]  # per sensor (yaw rad, sigma rad; infinite: none)
    headings_held: dict  # per sensor whose heading was held at its accelerometer's (mocap.calibration.headings)
    rechecked: dict  # per sensor whose mounting was solved again (mocap.calibration.plausible)
    left_out: dict[str, str]  # sensors left out -> why
    layout: _core.KeypointLayout  # step 4b's sites, or step 4's layout
    thetas: np.ndarray  # the window's poses
    directions: np.ndarray  # (3 x keypoints, kept)


def _solve_window(w: _Window, start: _Start, frames: list, starts: list, options: _core.CalibrationOptions,
                  dense: bool, quick: bool, site_std: float) -> _Solved:
    """Step 4, its accelerometer headings and step 4 again with them, then 4b (site_std > 0)."""
    model = prior.load()

    def solve(sites: list, heading_priors: list | None = None):  # step 4 from these IMU sites (and priors)
        if heading_priors is not None:
            options.heading_priors = heading_priors
        return _core.calibrate_window(start.skeleton, w.rig, start.layout, sites, model, frames, starts, options)

    try:
        result = solve(start.sites)
        accelerometer = _accelerometer_headings(result, w.rig, w.detections, w.times, None if quick else w.readings,
                                                dense)
        headings_held, held_out = {}, {}
        if any(np.isfinite(sigma) for _, sigma in accelerometer.values()):  # step 4 again, with them
            options.heading_priors = [np.array(accelerometer[s.name]) for s in start.sites]
            result = solve(start.sites)
            result, headings_held, held_out = headings.recheck(
                lambda priors: solve(start.sites, priors), result, accelerometer, options.heading_priors)
        result, rechecked, left_out = plausible.recheck(solve, result, np.asarray(model.mean))
        left_out.update(held_out)
        layout, thetas, directions = (_estimate_sites(result, w.rig, frames, options, site_std) if site_std > 0
                                      else (result.layout, result.thetas, np.zeros((0, 0))))
    except ValueError as e:
        raise InputError(f"calibration: {e}") from None
    return _Solved(result, accelerometer, headings_held, rechecked, left_out, layout, thetas, directions)


def _report(w: _Window, start: _Start, solved: _Solved, frames: int, quick: bool, sites_estimated: bool,
            pose_name: str | None, held_frames: int) -> dict:
    result, skel = solved.result, start.skeleton
    return {
        "window_start_s": 0.0, "window_s": float(w.times[-1] - w.times[0]), "frames": frames, "step": w.step,
        "quick": quick,
        "iterations": result.iterations, "converged": result.converged,
        "cost": {"start": result.initial_cost, "end": result.final_cost},
        "scales_start": start.estimate.scales,  # step 1, of the default skeleton's groups
        "scales_window": dict(zip(LENGTH_GROUPS, (float(s) for s in result.scales))),  # step 4, of step 1's
        "shifts_window_m": {g: np.asarray(d).tolist() for g, d in zip(SHIFT_GROUPS, result.shifts)},
        "sites_estimated": sites_estimated, "site_directions_kept": int(solved.directions.shape[1]),
        "calibration_pose": pose_name, "calibration_pose_frames": held_frames,
        "headings_held": solved.headings_held, "mountings_rechecked": solved.rechecked,
        "imus_left_out": solved.left_out,
        "imus": {s.name: {"bone": skel.bone_names[s.bone], "first_residual_deg": r0, "residual_deg": r,
                          "heading_deg": float(np.degrees(np.arctan2(s.reference[1, 0], s.reference[0, 0]))),
                          **headings.accelerometer_report(*solved.accelerometer[s.name]),
                          "mount": rotations.log(np.asarray(s.mount)).tolist()}
                 for s, r0, r in zip(result.imus, start.residuals_deg, result.imu_residual_deg)}}


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


def _window_motion(skel, rig, layout, imus: list, detections, times, readings: ImuReadings) -> np.ndarray:
    """(F, 66) the window's consecutive frames solved with a calibration, E_A off (what the
    accelerometers are compared with)."""
    options = _video_motion()
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
    readings = readings.only([s.name for s in imus])  # a sensor left out has no site
    thetas = _window_motion(skel, rig, layout, imus, detections, times, readings)
    out = {}
    for i, s in enumerate(imus):
        placed = imu_position.estimate(skel, s, thetas, times, readings.quaternions[: len(times), i],
                                       readings.accelerations[: len(times), i])
        s.offset = placed.offset
        out[s.name] = {"offset_m": placed.offset.tolist(), "estimated": placed.frames > 0, "frames": placed.frames,
                       "residual_ms2": placed.residual_ms2}
    return out
