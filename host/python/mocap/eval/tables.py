"""The paper's tables and plots on the test clips (`mocap eval --table paper`).

Writes docs/results.md (tables, with the command that regenerates them), the raw results
as JSON beside it, and PNG plots under docs/results/.
"""

from __future__ import annotations

import dataclasses
import json
import logging
from pathlib import Path

import numpy as np

from mocap import paths
from mocap.eval import simulated as evaluation
from mocap.eval import tables_calibration, tables_floors
from mocap.model import prior
from mocap.sim import take

log = logging.getLogger(__name__)

# The paper's terms: without E_A, E_M (not the paper's) would stand in for it, so it goes too.
ABLATIONS = [("IMU (E_R, E_A)", ["R", "A", "M"]), ("Ori. (E_R)", ["R"]), ("Acc. (E_A)", ["A", "M"]),
             ("Pos. (E_P)", ["P"]), ("Prior (E_PP, E_PD)", ["PP", "PD"]), ("Prior proj. (E_PP)", ["PP"]),
             ("Prior dev. (E_PD)", ["PD"])]
SUBSAMPLING = [(1, 1), (4, 1), (8, 2), (8, 1), (16, 2)]
# The defaults against one step either side, on the validation clips (never on the test
# clips): E_A's velocity filter and weight, then E_P, E_R and E_PD.
TUNING = [("defaults", []),
          ("E_A as the slide: gain 1, 30 m/s^2", ["velocity_gain=1", "acceleration.weight=0.00111"]),
          ("E_A gain 1", ["velocity_gain=1"]),
          ("E_A 30 m/s^2", ["acceleration.weight=0.00111"]),
          ("E_A 10 m/s^2", ["acceleration.weight=0.01"]),
          ("E_P 3 px", ["position.weight=0.111"]), ("E_P 10 px", ["position.weight=0.01"]),
          ("E_R 1.15 deg", ["orientation.weight=2500"]), ("E_R 4 deg", ["orientation.weight=204"]),
          ("E_PD x3", ["pca_deviation.weight=3"]), ("E_PD x0.3", ["pca_deviation.weight=0.3"]),
          ("E_G 1 cm", ["ground.weight=10000"]), ("E_G 4 cm", ["ground.weight=625"]),
          ("exact prediction (no shift)", ["prediction_slack=0"]), ("prediction slack 2", ["prediction_slack=2"])]


def test_clips() -> list[Path]:
    root = paths.shared_file("data/mocap")
    return [root / c for c in sorted(prior.test_clips())]


def validation_clips() -> list[Path]:
    root = paths.shared_file("data/mocap")
    return [root / c for c in sorted(prior.validation_clips())]


def _run(clips, config, omit=(), baseline=None, seed=0, settings=()) -> dict:
    results = [evaluation.evaluate(c, config, list(omit), seed, list(settings), baseline=baseline) for c in clips]
    return evaluation.summarise(results)


CAMERAS_LOST_AT_S = 2.0  # IMUs only from then on, after 8 cameras


def compute(seed: int = 0) -> dict:
    clips = test_clips()
    out = {"seed": seed, "clips": [c.relative_to(paths.shared_file("data/mocap")).as_posix() for c in clips]}
    out["configurations"] = {p: _run(clips, take.Config(preset=p), seed=seed) for p in take.PRESETS}
    out["estimated"] = tables_calibration.compute(clips, seed)
    out["floors"] = tables_floors.compute(clips, seed)
    out["baselines"] = {b: _run(clips, take.Config(preset="hq13"), baseline=b, seed=seed)
                        for b in ("triangulation", "imu-only")}
    out["baselines"]["imu-only-6"] = _run(clips, take.Config(preset="hq6"), baseline="imu-only", seed=seed)
    out["ablations"] = {}
    for imus in ("hq13", "hq6"):
        full = out["configurations"][imus]
        out["ablations"][imus] = {name: _run(clips, take.Config(preset=imus), omit, seed=seed) for name, omit in ABLATIONS}
        out["ablations"][imus]["full"] = full
    out["cameras"] = {n: _run(clips, take.Config(preset="hq13", cameras=n), seed=seed) for n in range(1, 9)}
    out["cameras_lost"] = _run(clips, take.Config(preset="hq13", cameras_lost_at_s=CAMERAS_LOST_AT_S), seed=seed)
    out["subsampling"] = {f"{b} of {p}": _run(clips, take.Config(preset="hq13", detect_every=(p, b)), seed=seed)
                          for p, b in SUBSAMPLING}
    out["site_offsets_off"] = {m or "fused": _run(clips, dataclasses.replace(
        take.Config(preset="hq13"), detector=dataclasses.replace(take.Config().detector, site_offsets=False)),
        baseline=m, seed=seed) for m in (None, "triangulation")}
    val = validation_clips()
    out["tuning"] = {"clips": [c.relative_to(paths.shared_file("data/mocap")).as_posix() for c in val]}
    for preset in ("hq13", "hs6"):
        out["tuning"][preset] = {name: _run(val, take.Config(preset=preset), seed=seed, settings=settings)
                                 for name, settings in TUNING}
    return out


def _clip_name(result: dict) -> str:
    return Path(result["clip"]).stem


def _row(name: str, summary: dict, key: str, fmt: str = "{:.1f}") -> str:
    cells = [fmt.format(c[key]) for c in summary["clips"]]
    return f"| {name} | " + " | ".join(cells) + f" | **{fmt.format(summary[key])}** |"


def _configurations(r: dict) -> list[str]:
    """Position and orientation error per clip, velocity error and floor, per configuration."""
    conf, base = r["configurations"], r["baselines"]
    clips = [_clip_name(c) for c in conf["hq13"]["clips"]]
    head = "| | " + " | ".join(clips) + " | mean |\n|---|" + "---|" * (len(clips) + 1)
    rows = [("13 IMU, HQ", conf["hq13"]), ("13 IMU, HS", conf["hs13"]), ("6 IMU, HQ", conf["hq6"]),
            ("6 IMU, HS", conf["hs6"]), ("video only (triangulation baseline)", base["triangulation"]),
            ("IMU only (13 IMUs, root aligned)", base["imu-only"]),
            ("IMU only (6 IMUs, root aligned)", base["imu-only-6"])]
    lines = ["## Input configurations (paper: \"Number of IMUs and quality/speed trade-off\")", "",
             "Position error (cm)", "", head]
    lines += [_row(name, s, "pos_error_cm") for name, s in rows]
    lines += ["", "Orientation error (deg)", "", head]
    lines += [_row(name, s, "ori_error_deg") for name, s in rows]
    lines += ["", "Velocity error (cm/s, jitter) and floor", "", "| | velocity error | floor_cm | solve ms (median) |",
              "|---|---|---|---|"]
    short = ["13 IMU, HQ", "13 IMU, HS", "6 IMU, HQ", "6 IMU, HS", "video only", "IMU only, 13", "IMU only, 6"]
    lines += [f"| {name} | {s['vel_error_cms']:.1f} | {s['floor_cm']:.2f} | {s['solve_ms_median']:.2f} |"
              for name, (_, s) in zip(short, rows)]
    off = r["site_offsets_off"]
    return lines + ["", "With the detector's site offsets off (13 IMU, HQ): fused "
                    f"{off['fused']['pos_error_cm']:.2f} cm, video-only baseline "
                    f"{off['triangulation']['pos_error_cm']:.2f} cm."]


def _ablations(r: dict) -> list[str]:
    lines = ["## Omitting terms (paper: ratios to the full cost function)", "",
             "| terms omitted | 13 IMUs pos. | 13 IMUs ori. | 6 IMUs pos. | 6 IMUs ori. |", "|---|---|---|---|---|"]
    for name, _ in ABLATIONS:
        cells = []
        for imus in ("hq13", "hq6"):
            a, full = r["ablations"][imus][name], r["ablations"][imus]["full"]
            cells += [f"{a['pos_error_cm'] / full['pos_error_cm']:.2f}", f"{a['ori_error_deg'] / full['ori_error_deg']:.2f}"]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return lines + ["", "Without E_R no sensor orients the bones, and E_P's loss is wider on such frames "
                        "(`video_only_position_loss_scale`, as on video-only takes): the rows without E_R measure both."]


def _cameras_and_subsampling(r: dict) -> list[str]:
    lines = ["## Number of cameras (13 IMU, HQ)", "", "| cameras | " + " | ".join(str(n) for n in r["cameras"]) + " |",
             "|---|" + "---|" * len(r["cameras"]),
             "| position (cm) | " + " | ".join(f"{s['pos_error_cm']:.1f}" for s in r["cameras"].values()) + " |",
             "| orientation (deg) | " + " | ".join(f"{s['ori_error_deg']:.1f}" for s in r["cameras"].values()) + " |",
             "", "With one camera, depth along its rays is seen only through the body's apparent size (and at the feet "
             "through the floor, E_G, which `mocap eval` takes from the true poses): the motion terms' prediction follows "
             "the keypoints there rather than dead-reckoning the body 0.8-6 m away as it did (the prediction shift, "
             "host/README.md, \"The per-frame solve\"). Without the detector's systematic keypoint offsets "
             "(`--site-offsets off`) one camera scores 5.0 cm.",
             ""] + _cameras_lost(r) + ["", "## Detection subsampling (13 IMU, 8 cameras)", "",
             "| detections on | position (cm) | orientation (deg) | velocity (cm/s) |", "|---|---|---|---|"]
    for name, s in r["subsampling"].items():
        lines.append(f"| {name} frames | {s['pos_error_cm']:.1f} | {s['ori_error_deg']:.1f} | {s['vel_error_cms']:.1f} |")
    return lines


def _cameras_lost(r: dict) -> list[str]:
    clips = r["cameras_lost"]["clips"]
    cells, worst = [], []
    for after in evaluation.DRIFT_AFTER_S:
        e = [c["cameras_lost"][f"{after:g}s"] for c in clips if c["cameras_lost"][f"{after:g}s"] is not None]
        cells.append(f"{np.mean(e):.1f} ({len(e)})" if e else "-")
        worst.append(f"{max(e):.1f}" if e else "-")
    return [f"## Cameras lost (13 IMU, HQ: 8 cameras for {CAMERAS_LOST_AT_S:g} s, then IMUs only)", "",
            "| after the loss | " + " | ".join(f"{a:g} s" for a in evaluation.DRIFT_AFTER_S) + " |",
            "|---|" + "---|" * len(evaluation.DRIFT_AFTER_S),
            "| joint centres (cm), mean over the clips that long (clips) | " + " | ".join(cells) + " |",
            "| worst clip (cm) | " + " | ".join(worst) + " |", "",
            "Without keypoints the root's position is dead-reckoned from the accelerometers (E_A), and every such "
            "frame's `PoseFrame` says so (`QUALITY_POSITION_UNCONSTRAINED`). The floor (E_G, its loss widened on "
            "frames without keypoints: `ground_unobserved_scale`) holds the height; the horizontal drift is the "
            "accelerometers' (bias, tilt error) and grows with time. When the keypoints return the pose is "
            "re-acquired from them and the drift spread over the velocity (host/README.md). "
            f"`mocap eval --motion CLIP --calibration oracle --cameras-lost-at {CAMERAS_LOST_AT_S:g} --json OUT` "
            "gives one clip's figures."]


def _tuning(r: dict) -> list[str]:
    tune = r["tuning"]
    lines = ["## Tuning (validation clips: " + ", ".join(tune["clips"]) + ")", "",
             "The solver's defaults against one step either side, on clips of performers in neither the prior's",
             "training nor the test set (`host/data/motion_split.json`). Position cm / orientation deg / velocity cm/s.",
             "", "| settings | `--set` | 13 IMU HQ | 6 IMU HS |", "|---|---|---|---|"]
    for name, settings in TUNING:
        cells = [f"{tune[p][name]['pos_error_cm']:.2f} / {tune[p][name]['ori_error_deg']:.1f} / "
                 f"{tune[p][name]['vel_error_cms']:.0f}" for p in ("hq13", "hs6")]
        lines.append(f"| {name} | {' '.join(settings) or '-'} | " + " | ".join(cells) + " |")
    return lines


def markdown(r: dict, command: str) -> str:
    lines = ["# Results on the test clips", "",
             f"Regenerate everything on this page: `{command}` (seed {r['seed']}, 16 minutes on one core of "
             "a 2-core AMD EPYC).",
             "Simulated studio of `host/python/mocap/sim/` on the test clips of `host/data/motion_split.json`;",
             "oracle calibration (true skeleton and sensor mounting) except in \"Estimated calibration\"; raw numbers",
             "in `docs/results.json`. Each take reaches the solver and the calibration as the live host's own",
             "input path delivers it: its camera frames and IMU samples sent as the studio's messages",
             "(`mocap.sim.messages`: keypoints at the wire's float32 precision, the IMUs sampled on the camera",
             "trigger) and synchronised by the C++ `InputPath` that `mocapd` runs.",
             "Real video (the edge detector and a video-only solve of Pose2Sim's Balancing trial):",
             "`docs/results_real.md`.", ""]
    lines += _configurations(r) + [""] + tables_floors.markdown(r) + [""] + _ablations(r) + [""] + _cameras_and_subsampling(r) + [""] + _tuning(r)
    lines += ["", "## Accuracy targets", "", "| target | measured | |", "|---|---|---|"]
    lines += [f"| {t} | {m} | {'met' if ok else '**missed**'} |" for t, m, ok in targets(r)]
    lines += tables_calibration.markdown(r)
    lines += ["", "## Plots", "", "![per-joint error](results/per_joint.png)", "", "![error over time](results/over_time.png)", ""]
    return "\n".join(lines)


def targets(r: dict) -> list[tuple[str, str, bool]]:
    """(target, measured, met) for each accuracy target."""
    c, b, off = r["configurations"], r["baselines"], r["site_offsets_off"]
    hq, tri, imu, imu6 = c["hq13"], b["triangulation"], b["imu-only"], b["imu-only-6"]
    a13, a6 = r["ablations"]["hq13"], r["ablations"]["hq6"]

    def ratios(a, name):
        return " / ".join(f"x{a[name][k] / a['full'][k]:.2f}" for k in ("pos_error_cm", "ori_error_deg"))

    def worse(a, name):
        return all(a[n][k] > a["full"][k] for n in (name,) for k in ("pos_error_cm", "ori_error_deg"))

    return [
        ("13 IMU HQ position within 0.1 cm of floor_cm, or below",
         f"{hq['pos_error_cm']:.2f} vs {hq['floor_cm']:.2f} cm", hq["pos_error_cm"] <= hq["floor_cm"] + 0.1),
        ("13 IMU HQ orientation <= 5 deg", f"{hq['ori_error_deg']:.1f} deg", hq["ori_error_deg"] <= 5.0),
        ("13 IMU HQ velocity error <= half the triangulation baseline's",
         f"{hq['vel_error_cms']:.0f} vs {tri['vel_error_cms']:.0f} cm/s", hq["vel_error_cms"] <= tri["vel_error_cms"] / 2),
        ("site offsets off: fused >= 25% below the triangulation baseline",
         f"{off['fused']['pos_error_cm']:.2f} vs {off['triangulation']['pos_error_cm']:.2f} cm",
         off["fused"]["pos_error_cm"] <= 0.75 * off["triangulation"]["pos_error_cm"]),
        ("every fused configuration below the IMU-only orientation error (same IMU set)",
         ", ".join(f"{p} {s['ori_error_deg']:.1f}" for p, s in c.items())
         + f" vs {imu['ori_error_deg']:.1f} (13), {imu6['ori_error_deg']:.1f} (6) deg",
         all(s["ori_error_deg"] < (imu6 if p.endswith("6") else imu)["ori_error_deg"] for p, s in c.items())),
        ("6 IMU HS velocity error below the triangulation baseline's",
         f"{c['hs6']['vel_error_cms']:.0f} vs {tri['vel_error_cms']:.0f} cm/s", c["hs6"]["vel_error_cms"] < tri["vel_error_cms"]),
        ("omitting E_P raises position error at least tenfold (13 and 6 IMUs)",
         f"x{a13['Pos. (E_P)']['pos_error_cm'] / a13['full']['pos_error_cm']:.0f}, "
         f"x{a6['Pos. (E_P)']['pos_error_cm'] / a6['full']['pos_error_cm']:.0f}",
         all(a["Pos. (E_P)"]["pos_error_cm"] >= 10 * a["full"]["pos_error_cm"] for a in (a13, a6))),
        ("omitting E_R or the prior worsens position and orientation (13 and 6 IMUs)",
         f"E_R {ratios(a13, 'Ori. (E_R)')} (13), {ratios(a6, 'Ori. (E_R)')} (6); prior "
         f"{ratios(a13, 'Prior (E_PP, E_PD)')} (13), {ratios(a6, 'Prior (E_PP, E_PD)')} (6); pos. / ori.",
         all(worse(a, n) for a in (a13, a6) for n in ("Ori. (E_R)", "Prior (E_PP, E_PD)"))),
    ]


def plots(r: dict, folder: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    joints = list(r["configurations"]["hq13"]["clips"][0]["per_joint"])
    fig, ax = plt.subplots(figsize=(12, 4))
    names = list(r["configurations"]) + ["triangulation"]
    for i, name in enumerate(names):
        s = r["configurations"].get(name) or r["baselines"][name]
        err = [np.mean([c["per_joint"][j]["pos_cm"] for c in s["clips"]]) for j in joints]
        ax.bar(np.arange(len(joints)) + 0.18 * i, err, width=0.18, label=name)
    ax.set_xticks(np.arange(len(joints)) + 0.36, joints, rotation=60, ha="right")
    ax.set_ylabel("position error (cm)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(folder / "per_joint.png", dpi=100)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(12, 3.5))
    for name in names:
        s = r["configurations"].get(name) or r["baselines"][name]
        ax.plot(s["clips"][0]["pos_error_cm_per_frame"], label=name, lw=1)
    ax.set_xlabel(f"frame ({_clip_name(r['configurations']['hq13']['clips'][0])}, 60 Hz)")
    ax.set_ylabel("mean joint position error (cm)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(folder / "over_time.png", dpi=100)
    plt.close(fig)


def compact(r):
    """The results without per-frame series (they only feed the plots), to 3 decimals."""
    if isinstance(r, dict):
        return {k: compact(v) for k, v in r.items() if k != "pos_error_cm_per_frame"}
    if isinstance(r, list):
        return [compact(v) for v in r]
    return round(r, 3) if isinstance(r, float) else r


def write(seed: int, docs: Path, command: str) -> dict:
    r = compute(seed)
    docs.mkdir(parents=True, exist_ok=True)
    (docs / "results.md").write_text(markdown(r, command))
    plots(r, docs / "results")
    (docs / "results.json").write_text(json.dumps(compact(r)) + "\n")
    log.info("wrote %s", docs / "results.md")
    return r
