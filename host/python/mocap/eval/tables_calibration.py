"""The estimated-calibration part of `mocap eval --table paper`: every preset solved
with the calibration each take estimates from its own first seconds, beside the oracle rows,
and how close the estimates come to the truth."""

from __future__ import annotations

import numpy as np

from mocap.eval import simulated as evaluation
from mocap.sim import take


def compute(clips, seed: int) -> dict:
    out = {}
    for preset in take.PRESETS:
        results = [evaluation.evaluate(c, take.Config(preset=preset), [], seed, calibration="estimated") for c in clips]
        out[preset] = evaluation.summarise(results)
    return out


def _errors(summary: dict, key: str) -> np.ndarray:
    return np.array([i[key] for c in summary["clips"] for i in c["calibration_errors"]["imus"].values()])


def _sites(summary: dict, key: str) -> np.ndarray:
    return np.array([k[key] for c in summary["clips"] for k in c["calibration_errors"]["sites"].values()])


def _stats(values: np.ndarray, unit: str) -> str:
    v = values[np.isfinite(values)]
    return f"{np.median(v):.1f} / {np.percentile(v, 90):.1f} / {v.max():.1f} {unit}"


def markdown(r: dict) -> list[str]:
    est, conf, tri = r["estimated"], r["configurations"], r["baselines"]["triangulation"]
    lines = ["", "## Estimated calibration", "",
             "Each take calibrates itself from its first 5 s with motion (`mocap.calibration.window`, `informative`:",
             "skeleton, keypoint sites, IMU mountings, headings and positions; nothing of the truth is used), then is",
             "solved with that calibration.",
             "Position and velocity errors over the 13 anatomical joint centres (`mocap.model.joint_centres`): a skeleton",
             "estimated from keypoints puts its pelvis origin, spine joints and clavicles where its own convention does,",
             "which no keypoint observes; the 21-bone figure is given too. Triangulation baseline: the same HQ takes.", "",
             "| configuration | joint centres (cm) estimated / oracle | velocity (cm/s) estimated / oracle "
             "| 21 bones (cm) estimated / oracle |", "|---|---|---|---|"]
    for p, s in est.items():
        o = conf[p]
        lines.append(f"| {p} | {s['joint_centres_pos_cm']:.2f} / {o['joint_centres_pos_cm']:.2f} | "
                     f"{s['joint_centres_vel_cms']:.1f} / {o['joint_centres_vel_cms']:.1f} | "
                     f"{s['pos_error_cm']:.2f} / {o['pos_error_cm']:.2f} |")
    lines.append(f"| triangulation baseline (HQ) | {tri['joint_centres_pos_cm']:.2f} | {tri['joint_centres_vel_cms']:.1f} | "
                 f"{tri['pos_error_cm']:.2f} |")
    hq = est["hq13"]
    clips = " | ".join(f"{c['joint_centres_pos_cm']:.2f} / {o['joint_centres_pos_cm']:.2f}"
                       for c, o in zip(hq["clips"], conf["hq13"]["clips"]))
    names = " | ".join(c["clip"].rsplit("/", 1)[-1].removesuffix(".bvh") for c in hq["clips"])
    lengths = np.array([abs(v) for c in hq["clips"] for v in c["calibration_errors"]["limb_length_cm"].values()])
    lines += ["", "Per clip (13 IMU HQ, joint centres cm, estimated / oracle):", "", f"| {names} |",
              "|" + "---|" * len(hq["clips"]), f"| {clips} |", "",
              "How close the estimates come (13 IMU HQ, all sensors of all clips; median / 90th percentile / max):", "",
              f"- heading: {_stats(_errors(hq, 'heading_deg'), 'deg')}",
              f"- mounting, the bone's axis in the sensor frame (what video observes): {_stats(_errors(hq, 'mount_axis_deg'), 'deg')}",
              f"- mounting in full (the twist about the bone's axis is set by the pose prior, not observed): "
              f"{_stats(_errors(hq, 'mount_deg'), 'deg')}",
              f"- sensor position on the segment: {_stats(_errors(hq, 'offset_cm'), 'cm')}",
              f"- limb lengths (thigh, shin, upper arm, forearm): {_stats(lengths, 'cm')}",
              f"- keypoint sites (where the detector's keypoints sit on their bones): {_stats(_sites(hq, 'estimated_cm'), 'cm')}"
              f" (the layout's: {_stats(_sites(hq, 'layout_cm'), 'cm')}); along the directions the window observed: "
              f"{_stats(_sites(hq, 'observed_estimated_cm'), 'cm')} (the layout's: {_stats(_sites(hq, 'observed_layout_cm'), 'cm')})",
              "",
              "| target | measured | |", "|---|---|---|"]
    lines += [f"| {t} | {m} | {'met' if ok else '**missed**'} |" for t, m, ok in targets(r)]
    return lines


def targets(r: dict) -> list[tuple[str, str, bool]]:
    hq, oracle, tri = r["estimated"]["hq13"], r["configurations"]["hq13"], r["baselines"]["triangulation"]
    heading, axis, full = (_errors(hq, k) for k in ("heading_deg", "mount_axis_deg", "mount_deg"))
    lengths = np.array([abs(v) for c in hq["clips"] for v in c["calibration_errors"]["limb_length_cm"].values()])
    sites = _sites(hq, "observed_estimated_cm")
    p, v, po = hq["joint_centres_pos_cm"], hq["joint_centres_vel_cms"], oracle["joint_centres_pos_cm"]
    return [
        ("position <= 90% of the triangulation baseline's (13 IMU HQ, joint centres)",
         f"{p:.2f} vs {tri['joint_centres_pos_cm']:.2f} cm ({100 * p / tri['joint_centres_pos_cm']:.0f}%)",
         p <= 0.9 * tri["joint_centres_pos_cm"]),
        ("velocity <= 50% of the triangulation baseline's",
         f"{v:.1f} vs {tri['joint_centres_vel_cms']:.1f} cm/s ({100 * v / tri['joint_centres_vel_cms']:.0f}%)",
         v <= 0.5 * tri["joint_centres_vel_cms"]),
        ("position within 15% of the oracle calibration's", f"{p:.2f} vs {po:.2f} cm ({100 * (p / po - 1):+.0f}%)",
         p <= 1.15 * po),
        ("headings within 2 deg", f"median {np.nanmedian(heading):.1f}, max {np.nanmax(heading):.1f} deg",
         bool(np.nanmax(heading) <= 2.0)),
        ("mountings within 2 deg", f"axis median {np.nanmedian(axis):.1f}, in full median {np.nanmedian(full):.1f} deg",
         bool(np.nanmax(full) <= 2.0)),
        ("bone lengths within 1 cm", f"limbs median {np.median(lengths):.1f}, max {lengths.max():.1f} cm",
         bool(lengths.max() <= 1.0)),
        ("site offsets within 1 cm along the observable directions (median)",
         f"median {np.median(sites):.1f}, 90th percentile {np.percentile(sites, 90):.1f} cm (the layout's "
         f"{np.median(_sites(hq, 'observed_layout_cm')):.1f} / {np.percentile(_sites(hq, 'observed_layout_cm'), 90):.1f})",
         bool(np.median(sites) <= 1.0)),
        ("stretch: joint centres below floor_cm", f"{p:.2f} vs {hq['floor_cm']:.2f} cm", bool(p < hq["floor_cm"])),
    ]
