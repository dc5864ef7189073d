"""The calibration report of a take folder's solve (OUTDIR/calibration.md), from its
calibration.json."""

from __future__ import annotations


def _position(w: dict, name: str) -> str:
    """The offset and position columns of a sensor's row."""
    if name in w.get("imus_left_out", {}):
        return "- | left out |"
    p = w["imu_positions"][name]
    return f"{', '.join(f'{100 * v:.1f}' for v in p['offset_m'])} | {'estimated' if p['estimated'] else 'usual place'}"


def _mountings(w: dict) -> list[str]:
    """What the window's checks did: headings held at their accelerometer's
    (mocap.calibration.headings), mountings solved again (mocap.calibration.plausible)."""
    lines = [f"- {name}: heading {h['window_deg']:.1f} deg against its accelerometer's {h['accelerometer_deg']:.1f} "
             f"± {h['sigma_deg']:.1f}: held there ({h['heading_deg']:.1f}), its orientations then fit "
             f"{h['residual_deg_held']:.2f} deg (before {h['residual_deg_before']:.2f})."
             for name, h in w.get("headings_held", {}).items()]
    for name, c in w.get("mountings_rechecked", {}).items():
        tries = ", ".join(f"{a}: {t['turn_deg']:.0f} deg" for a, t in c["tries"].items())
        lines.append(f"- {name}: its bone {c['turn_deg']:.0f} deg from the prior's mean pose; mounting turned half a "
                     f"turn about each axis ({tries}): {c.get('kept', 'none plausible')}.")
    for name, why in w.get("imus_left_out", {}).items():
        lines.append(f"- **{name} left out**: {why}.")
    return lines + [""] if lines else []


def markdown(r: dict) -> str:
    w = r["window"]
    rows = "\n".join(f"| {g} | {s:.3f} | {100 * r['skeleton']['lengths_m'][g]:.1f} cm | {r['skeleton']['frames_per_length'][g]} |"
                     if g in r["skeleton"]["lengths_m"] else f"| {g} | {s:.3f} | (overall scale) | 0 |"
                     for g, s in r["skeleton"]["scales"].items())
    refined = ", ".join(f"{g} x{s:.3f}" for g, s in w["scales_window"].items())
    shifts = ", ".join(f"{g} ({', '.join(f'{100 * v:+.1f}' for v in d)}) cm" for g, d in w["shifts_window_m"].items())
    change = r["solve"]["heading_change_deg"]
    accel = lambda i: ("-" if i["heading_accelerometer_deg"] is None  # noqa: E731
                       else f"{i['heading_accelerometer_deg']:.1f} ± {i['heading_accelerometer_sigma_deg']:.1f}")
    imus = "\n".join(f"| {name} | {i['bone']} | {i['heading_deg']:.1f} | {accel(i)} | {change.get(name, 0.0):+.1f} | "
                     f"{i['first_residual_deg']:.1f} | {i['residual_deg']:.2f} | {_position(w, name)} |"
                     for name, i in w["imus"].items())
    lines = [
        "# Calibration report", "",
        f"Skeleton, first estimate: {r['skeleton']['from_frames']} frames from {w['window_start_s']:.1f} s "
        "(triangulated keypoints,",
        "median distances, left and right pooled), as scales of the default skeleton's bone groups:", "",
        "| group | scale | measured | distances |", "|---|---|---|---|", rows, "",
        f"Window calibration ({w['frames']} frames of the {w['window_s']:.1f} s from {w['window_start_s']:.1f} s"
        f"{'' if r['window_motion_score_deg'] is None else ', IMUs tilting ' + format(r['window_motion_score_deg'], '.1f') + ' deg RMS'}"
        f", {w['iterations']} iterations, "
        f"cost {w['cost']['start']:.0f} -> {w['cost']['end']:.0f}):",
        f"lengths {refined}; shifts {shifts}. Keypoint sites: "
        f"{'estimated along ' + str(w['site_directions_kept']) + ' observed directions' if w['sites_estimated'] else 'the layout' + chr(39) + 's'}"
        f" (`layout.json`).",
        f"Calibration pose: {w['calibration_pose'] + '-pose held, ' + str(w['calibration_pose_frames']) + ' frames' if w['calibration_pose'] else 'none found'}.",
        ""]
    if w["imus"]:
        lines += ["Heading: from the window, with the accelerometer's (± its standard deviation) as a prior; change: "
                  "the heading tracking's correction at the take's end.", "",
                  "| sensor | bone | heading (deg) | accelerometer (deg) | change (deg) | start residual (deg) | "
                  "residual (deg) | offset (cm) | position |", "|---|---|---|---|---|---|---|---|---|", imus, "",
                  *_mountings(w)]
    else:
        lines += [f"IMUs not used: {r['imus_not_used_because']}." if r["imus_not_used_because"]
                  else "No IMUs: a video-only solve.", ""]
    lines += [f"Solve: {r['frames']} frames, {r['imus_used']} IMUs; statuses {r['solve']['statuses']}.", ""]
    left_out = r["solve"].get("distrusted", {})
    if left_out:
        lines += ["Sensors left out of the solve while the keypoints contradicted them (slipped, failed, or "
                  "mounted other than calibrated):", "",
                  "| sensor | first (s) | left out (s) |", "|---|---|---|",
                  *(f"| {name} | {s['first_s']:.2f} | {s['seconds']:.2f} |" for name, s in left_out.items()), ""]
    return "\n".join(lines)
