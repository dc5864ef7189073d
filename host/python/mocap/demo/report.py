"""The demo's report (OUT/report.md): what was played, how the session was calibrated, and
the figures of the run (mocap.demo.score)."""

from __future__ import annotations

from mocap.demo.studio import IMU_RATE, Studio


def calibration_line(studio: Studio, result: dict) -> str:
    if studio.calibration == "oracle":
        return "Calibration: the oracle (the simulation's true skeleton and IMU mounting)."
    if studio.calibration == "live":
        when = result.get("calibrated_from_s")
        after = result.get("calibrated", {}).get("joint_centres_pos_cm")
        return ("Calibration: live — mocapd started from video alone with the default skeleton; the live calibrator "
                "(`mocap calibrate --follow`) published the subject's calibration as soon as the IMUs had moved "
                "enough, estimated from the live streams (details in `session/calibrated/calibration.json`): "
                + ("never, in this take." if when is None else
                   f"solved with the IMUs from {when:.1f} s of the take on"
                   + ("" if after is None else f", joint centres {after:.2f} cm from then") + ". Published: "
                   + ", ".join(f"{'quick' if c['quick'] else 'full'} at {c['take_s']:.1f} s"
                               for c in result.get("calibrations", [])) + "."))
    return ("Calibration: estimated by the host from the take's first 5 s with motion (skeleton, IMU mountings, "
            "headings and positions; `docs/calibration.md`, details in `session/calibration.json`): nothing of the "
            "truth.")


def _largest(corrections: dict) -> str:
    if not corrections:
        return "n/a"
    name = max(corrections, key=lambda k: abs(corrections[k]))
    return f"{corrections[name]:+.1f} deg ({name})"


def _left_out(spans: dict | None) -> str:
    if spans is None:
        return "n/a"
    return ", ".join(f"{name} from {s['first_s']:.1f} s for {s['seconds']:.1f} s" for name, s in spans.items()) or "none"


def report(result: dict, seconds: float, studio: Studio) -> str:
    def fmt(v, unit=""):
        return "n/a" if v is None else f"{v:.2f}{unit}"
    dropped = ", ".join(f"{k} {v}" for k, v in result["host_dropped"].items()) or "none"
    return "\n".join([
        "# mocap demo report", "",
        f"Simulated studio: Pose2Sim's Balancing trial (PyPI pose2sim 0.4.15, BSD-3) fitted to the skeleton and "
        f"looped to {seconds:.0f} s; {len(studio.camera_ids)} cameras at 60 fps (simulated detector errors), "
        f"13 IMUs at {IMU_RATE:.0f} Hz (simulated sensor errors); played in real time by one "
        "camera box per camera (the real box on the simulated backend) and the IMU hub reading simulated sensor "
        "nodes (a CAN bus served over TCP), over ZeroMQ on loopback; "
        "solved live by mocapd.", "",
        calibration_line(studio, result), "",
        "| figure | value |", "|---|---|",
        f"| frames captured | {result['frames']} |",
        f"| frames solved and received | {result['solved']} |",
        f"| frames dropped | {result['dropped']} |",
        f"| joint centre position error (mean, 13 joints) | {fmt(result.get('joint_centres_pos_cm'), ' cm')} |",
        f"| joint centre velocity error (mean) | {fmt(result.get('joint_centres_vel_cms'), ' cm/s')} |",
        f"| bone origin position error (mean, 21 bones) | {fmt(result.get('pos_error_cm'), ' cm')} |",
        f"| bone orientation error (mean, 21 bones; each bone's constant rest-frame offset removed) | "
        f"{fmt(result.get('ori_error_offset_removed_deg'), ' deg')} |",
        f"| bone orientation error with those offsets (mean) | {fmt(result.get('ori_error_deg'), ' deg')} |",
        f"| host latency p50 / p99 / max | {fmt(result['latency_p50_ms'])} / {fmt(result['latency_p99_ms'])} / "
        f"{fmt(result['latency_max_ms'], ' ms')} |",
        f"| inputs dropped by the host | {dropped} |",
        f"| heading tracking: largest correction at the end | {_largest(result['heading_corrections_deg'])} |",
        f"| sensors left out (the keypoints contradicted them) | {_left_out(result.get('distrusted'))} |", "",
        "Host latency: from the arrival of a frame's last input to the publication of its pose. Bone "
        "orientation: an estimated skeleton puts a bone's frame at rest differently from the simulation's (a "
        "constant rotation per bone over the take, which an animation retargeted onto any rig absorbs); with "
        "that constant removed, what remains is tracking error.", ""])
