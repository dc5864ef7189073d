"""The fused solver (or a baseline) on simulated takes of real motion: `mocap eval`. Each
take is simulated (mocap.sim.take), sent through the host's input path as the studio's
messages (mocap.sim.messages), calibrated from its own first seconds or given the truth's
calibration (oracle), solved frame by frame, and scored (mocap.eval.metrics), with the
per-frame solve time."""

from __future__ import annotations

import numpy as np

from mocap import _core, rotations
from mocap.calibration import informative, window
from mocap.calibration.calibration_input import CalibrationInput
from mocap.eval import baselines
from mocap.eval.metrics import calibration_errors, errors, floor_cm
from mocap.model.solver import Solver, distrust_spans, solver_options
from mocap.sim import messages as sim_messages
from mocap.sim import take as sim_take

TERMS = {"R": "orientation", "P": "position", "A": "acceleration", "PP": "pca_projection", "PD": "pca_deviation",
         "M": "motion", "G": "ground"}


def options_for(omit: list[str], settings: list[str] = ()) -> _core.SolverOptions:
    """Solver options with the omitted terms off and "name=value" settings applied."""
    options = solver_options(list(settings))
    for term in omit:
        t = getattr(options, TERMS[term])
        t.enabled = False
        setattr(options, TERMS[term], t)
    return options


def solve(t: sim_take.Take, options: _core.SolverOptions, calibration: window.Calibration | None = None,
          headings: list | None = None, distrusted: list | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Solved poses (F, 66) and solve times (F,) ms of a take, with the oracle calibration
    (the take's skeleton, nominal layout and true IMU sites) or an estimated one; `headings`,
    when given, receives each frame's heading corrections (rad, Solver.headings), and
    `distrusted` each frame's names of the sensors the solve left out (SolveResult.imus_distrusted)."""
    c = calibration
    solver = (Solver(t.skeleton, t.rig, t.layout, t.imus, options=options) if c is None
              else Solver(c.skeleton, t.rig, c.layout, c.imus, options=options))
    sites = t.imus if c is None else c.imus  # a calibration may leave some out
    names = [s.name for s in t.imus]
    columns = [names.index(s.name) for s in sites]  # the take's readings of the solver's sensors
    sensors = list(range(len(sites)))
    thetas, ms = np.zeros_like(t.thetas), np.zeros(len(t.thetas))
    for f in range(len(t.thetas)):
        kp = t.keypoints[f]
        cams = list(range(len(t.rig.cameras))) if kp is not None else []
        kp = kp if kp is not None else np.zeros((0, len(t.layout), 3))
        r = solver.solve(t.times[f], cams, kp, sensors, t.quaternions[f, columns], t.accelerations[f, columns])
        thetas[f], ms[f] = r.theta, r.solve_time_ms
        if headings is not None:
            headings.append(list(solver.headings))
        if distrusted is not None:
            distrusted.append([sites[i].name for i in r.imus_distrusted])
    return thetas, ms


def estimate_calibration(t: sim_take.Take, frames: list, **options) -> window.Calibration:
    """The take's calibration from its own seconds (mocap.calibration.window, with its keyword
    options) of its synchronised frames (sim_messages.delivered), chosen as `mocap solve
    --take` chooses them (informative.calibration_window): nothing of the truth is used (the
    IMU readings' reference frames are treated as unknown too). IMUs too still to calibrate
    are left out (the calibration has none)."""
    data = CalibrationInput.from_frames(frames, len(t.rig.cameras), t.layout.name, len(t.layout),
                                        [(s.name, s.bone) for s in t.imus])
    return informative.estimate(t.rig, data, **options)[0]


def evaluate(clip, config: sim_take.Config, omit: list[str], seed: int, settings: list[str] = (),
             baseline: str | None = None, calibration: str = "oracle", calibration_options: dict | None = None) -> dict:
    """Scores the fused solver, or a baseline: "imu-only" or "triangulation" (mocap.eval.baselines).
    calibration: "oracle" (the true skeleton and IMU mounting) or "estimated" (fused solver
    only; calibration_options: keyword options of window.estimate)."""
    rng = np.random.default_rng(seed)
    t, frames = sim_messages.delivered(sim_take.simulate(clip, config, rng))
    estimated = (estimate_calibration(t, frames, **(calibration_options or {}))
                 if calibration == "estimated" and baseline is None else None)
    if baseline == "imu-only":
        solved, ms = baselines.imu_only(t), np.zeros(len(t.thetas))
    elif baseline == "triangulation":
        solved, ms = baselines.video_only(t), np.zeros(len(t.thetas))
    else:
        options = options_for(omit, settings)
        if estimated and not any(s.startswith("heading_time_constant=") for s in settings):
            options = window.solver_options(options)
        if not any(s.startswith("floor_height=") for s in settings):  # E_G's floor: the window's, or the truth's
            options.floor_height = estimated.floor_height if estimated else _core.floor_height(t.skeleton, t.thetas)
        left_out: list[list[str]] = []
        solved, ms = solve(t, options, estimated, distrusted=left_out)
    result = errors(t.skeleton, t.thetas, solved, 1.0 / config.rate, estimated.skeleton if estimated else None)
    result.update({"clip": str(clip), "method": baseline or "fused", "preset": config.preset,
                   "cameras": len(t.rig.cameras),
                   "imus": len(t.imus), "omit": omit, "settings": list(settings),
                   "site_offsets": config.detector.site_offsets,
                   "seed": seed, "frames": len(t.thetas), "solve_ms_median": float(np.median(ms)),
                   "calibration": "estimated" if estimated else t.calibration, "floor_cm": floor_cm(t)})
    if baseline is None:
        result["distrusted"] = distrust_spans(t.times, left_out)
    if config.cameras_lost_at_s is not None:
        result["cameras_lost"] = drift(t, solved, config.cameras_lost_at_s, estimated.skeleton if estimated else None)
    if config.bends or config.slips:
        result["extremes"] = extreme_errors(t, solved, estimated.skeleton if estimated else t.skeleton, config)
    if estimated:
        result["calibration_report"] = estimated.report
        result["calibration_errors"] = calibration_errors(t, estimated)
    return result


def extreme_errors(t: sim_take.Take, solved: np.ndarray, solved_skeleton: _core.Skeleton,
                   config: sim_take.Config) -> dict:
    """Orientation errors (deg, mean and max) of each bent bone once fully bent, and of each
    slipped sensor's bone from 1 s after the slip (time to notice it) to the end."""
    names = t.skeleton.bone_names
    truth = np.array([t.skeleton.forward_kinematics(th)[0] for th in t.thetas])
    ours = np.array([solved_skeleton.forward_kinematics(th)[0] for th in solved])
    times = t.times - t.times[0]
    spans = [(f"bent {n}", names.index(n), b.from_s + b.ramp_s) for b in config.bends for n in b.bones]
    bones = {s.name: s.bone for s in t.imus}
    spans += [(f"slipped {s.sensor} ({names[bones[s.sensor]]})", bones[s.sensor], s.at_s + 1.0) for s in config.slips]
    out = {}
    for label, j, from_s in spans:
        after = times >= from_s
        e = np.degrees(rotations.angle_between(ours[after, j], truth[after, j])) if after.any() else np.array([np.nan])
        out[label] = {"mean_deg": float(e.mean()), "max_deg": float(e.max())}
    return out


DRIFT_AFTER_S = (0.5, 1.0, 2.0, 4.0)


def drift(t: sim_take.Take, solved: np.ndarray, lost_at_s: float, solved_skeleton=None) -> dict:
    """Mean joint-centre error (cm) at each of DRIFT_AFTER_S seconds after the cameras were
    lost (null past the take's end)."""
    times = t.times - t.times[0]
    ours_skeleton = solved_skeleton or t.skeleton
    out = {}
    for after in DRIFT_AFTER_S:
        f = int(np.searchsorted(times, lost_at_s + after))
        if f >= len(times):
            out[f"{after:g}s"] = None
            continue
        ours, truth = ours_skeleton.forward_kinematics(solved[f])[1], t.skeleton.forward_kinematics(t.thetas[f])[1]
        out[f"{after:g}s"] = float(np.linalg.norm(ours - truth, axis=1).mean() * 100)
    return out


def summarise(results: list[dict]) -> dict:
    """Means over clips (weighted by frames) of the headline metrics, and every clip's result."""
    frames = np.array([r["frames"] for r in results], dtype=float)
    mean = {k: float(np.average([r[k] for r in results], weights=frames))
            for k in ("pos_error_cm", "ori_error_deg", "ori_error_offset_removed_deg", "vel_error_cms",
                      "joint_centres_pos_cm", "joint_centres_vel_cms", "floor_cm")}
    first = results[0]
    return {**mean, "frames": int(frames.sum()), "solve_ms_median": float(np.median([r["solve_ms_median"] for r in results])),
            "calibration": first["calibration"], "method": first["method"], "preset": first["preset"],
            "cameras": first["cameras"],
            "imus": first["imus"], "omit": first["omit"], "site_offsets": first["site_offsets"], "seed": first["seed"],
            "clips": results}
