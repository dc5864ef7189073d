"""`mocap eval --table heading`: heading tracking (SolverOptions.heading_time_constant, and
heading_baseline_s) on a long take of the demo motion, with the window's calibration and
with the true one, at the simulation's default heading drift and at ten times it (a
magnetically disturbed studio)."""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap.eval import metrics
from mocap.eval import simulated as evaluation
from mocap.sim import demo_motion, imu
from mocap.sim import messages as sim_messages
from mocap.sim import take as sim_take

DRIFTS = (0.5, 5.0)  # deg/sqrt(min)
# (calibration, heading_time_constant s (0: off), heading_baseline_s (0: none))
RUNS = (("estimated", 0.0, 0.0), ("estimated", 1.0, 0.0), ("oracle", 0.0, 0.0), ("oracle", 1.0, 0.0),
        ("oracle", 1.0, 5.0))


def rows(seconds: float = 60.0, seed: int = 1) -> list[dict]:
    """Per drift, calibration and time constant: joint centres (cm), bone orientations (deg)
    and the headings' error over the last 10 s (median and mean, deg)."""
    skeleton, thetas, dt = demo_motion.load_motion(60.0, seconds)
    out = []
    for drift in DRIFTS:
        config = sim_take.Config(imu=dataclasses.replace(imu.ImuErrors(), heading_drift_deg_per_sqrt_min=drift))
        t, frames = sim_messages.delivered(sim_take.simulate_motion(skeleton, thetas, dt, config,
                                                                    np.random.default_rng(seed)))
        estimated = evaluation.estimate_calibration(t, frames)
        for calibration, tau, baseline in RUNS:
            c = estimated if calibration == "estimated" else None
            headings: list = []
            settings = [f"heading_time_constant={tau}", f"heading_baseline_s={baseline}"]
            solved, _ = evaluation.solve(t, evaluation.options_for([], settings), c, headings)
            e = metrics.errors(t.skeleton, t.thetas, solved, dt, c.skeleton if c else None)
            last = metrics.heading_errors_deg(t, c or t, np.array(headings))[-int(round(10.0 / dt)):]
            out.append({"drift": drift, "calibration": calibration, "time_constant_s": tau, "baseline_s": baseline,
                        "joint_centres_cm": e["joint_centres_pos_cm"], "bones_deg": e["ori_error_deg"],
                        "heading_median_deg": float(np.median(last)), "heading_mean_deg": float(last.mean())})
    return out


def markdown(rs: list[dict], seconds: float) -> str:
    lines = [f"Heading tracking, {seconds:.0f} s of the demo motion, 8 cameras + 13 IMUs (headings: last 10 s)", "",
             "| drift (deg/sqrt(min)) | calibration | tau (s) | baseline (s) | joint centres (cm) | bones (deg) | "
             "heading median (deg) | heading mean (deg) |", "|---|---|---|---|---|---|---|---|"]
    lines += [f"| {r['drift']} | {r['calibration']} | {r['time_constant_s']:g} | {r['baseline_s']:g} | "
              f"{r['joint_centres_cm']:.2f} | "
              f"{r['bones_deg']:.1f} | {r['heading_median_deg']:.1f} | {r['heading_mean_deg']:.1f} |" for r in rs]
    return "\n".join(lines) + "\n"
