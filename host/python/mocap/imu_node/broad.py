"""The node's orientation filter on the BROAD benchmark, beside VQF and Fusion.

BROAD (Laidig et al., Data 2021; ../shared/data/imu/broad, its MANIFEST): 18 trials of one
hand-moved IMU at 285.71 Hz with optical ground truth. The metric is the benchmark's: the
error quaternion e = q_est ⊗ q_ref⁻¹ (earth frame); total error 2·acos|e_w|, heading error
2·atan|e_z/e_w|, inclination error 2·acos√(e_w²+e_z²); RMSE (degrees) over the movement
samples where the reference is finite; means over trials. 6D results first lose their mean
heading offset (circular mean over the scored samples).

The split is fixed: the filter's settings were tuned on TUNING only; HELD_OUT is never used
for tuning. Filters compared: ours 9D / 6D (the C of firmware/core through ctypes), VQF 2.1
(PyPI ``vqf``, defaults) 9D / 6D, Fusion 1.3 (PyPI ``imufusion``) 9D with gain 0.5,
acceleration and magnetic rejection 10° and a recovery timeout of 5 s.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mocap import paths
from mocap.errors import DataMissingError, InputError
from mocap.imu_node import filter as node_filter

TUNING = ("01", "04", "06", "08", "10", "24", "26", "28")
HELD_OUT = ("02", "03", "05", "07", "09", "11", "12", "25", "29", "31")
METHODS = ("ours 9D", "ours 6D", "VQF 9D", "VQF 6D", "Fusion 9D")
MEASURES = ("total", "heading", "inclination")


@dataclass
class Trial:
    number: str  # "01"
    name: str  # file stem
    gyr: np.ndarray  # (n, 3) rad/s, sensor frame
    acc: np.ndarray  # (n, 3) m/s², gravity included
    mag: np.ndarray  # (n, 3) µT
    quat_ref: np.ndarray  # (n, 4) w, x, y, z sensor -> ENU, NaN where the markers were lost
    movement: np.ndarray  # (n,) bool, the scored samples
    rate_hz: float

    @property
    def disturbed(self) -> bool:
        return int(self.number) >= 20


def folder() -> Path:
    return paths.shared_file("data/imu/broad")


def load(numbers: Iterable[str] | None = None, root: Path | None = None) -> list[Trial]:
    """The trials with these numbers ("01".."31"), all 18 when None."""
    root = folder() if root is None else root
    files = {p.name[:2]: p for p in sorted(root.glob("[0-9][0-9]_*.npz"))}
    wanted = sorted(files) if numbers is None else [f"{int(n):02d}" for n in numbers]
    unknown = [n for n in wanted if n not in files]
    if unknown:
        raise InputError(f"no BROAD trial {', '.join(unknown)} in {root} (have {', '.join(files)})")
    trials = []
    for number in wanted:
        with np.load(files[number]) as data:
            trials.append(Trial(number, files[number].stem, data["gyr"], data["acc"], data["mag"], data["quat_ref"],
                                data["movement"].astype(bool), float(data["rate"])))
    return trials


def _multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, x1, y1, z1 = a.T
    w2, x2, y2, z2 = b.T
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=1)


def errors(q_est: np.ndarray, trial: Trial, remove_heading: bool = False) -> tuple[float, float, float]:
    """RMSE in degrees of (total, heading, inclination) over the trial's scored samples."""
    q_ref = trial.quat_ref.astype(float)
    scored = trial.movement & np.isfinite(q_ref).all(axis=1)
    e = _multiply(np.asarray(q_est, float)[scored], q_ref[scored] * np.array([1.0, -1.0, -1.0, -1.0]))
    if remove_heading:
        heading = 2.0 * np.arctan2(e[:, 3], e[:, 0])
        offset = np.arctan2(np.mean(np.sin(heading)), np.mean(np.cos(heading)))
        turn = np.array([[np.cos(offset / 2.0), 0.0, 0.0, -np.sin(offset / 2.0)]])
        e = _multiply(np.repeat(turn, len(e), axis=0), e)
    w = np.abs(e[:, 0])
    total = 2.0 * np.arccos(np.clip(w, 0.0, 1.0))
    heading = 2.0 * np.arctan(np.abs(e[:, 3]) / np.maximum(w, 1e-12))
    inclination = 2.0 * np.arccos(np.clip(np.sqrt(e[:, 0] ** 2 + e[:, 3] ** 2), 0.0, 1.0))
    return tuple(float(np.degrees(np.sqrt(np.mean(x ** 2)))) for x in (total, heading, inclination))


def run_ours(trial: Trial, use_mag: bool, settings: node_filter.Settings | None = None) -> np.ndarray:
    result = node_filter.run(trial.gyr, trial.acc, trial.mag if use_mag else None, 1.0 / trial.rate_hz, settings)
    return result.quaternions if use_mag else result.quaternions_6d


def _require(module: str, package: str):
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise DataMissingError(f"the comparison needs the PyPI package {package} (make setup installs it)") from None


def run_vqf(trial: Trial, use_mag: bool) -> np.ndarray:
    VQF = _require("vqf", "vqf").VQF  # noqa: N806 (a class)

    gyr, acc, mag = (np.ascontiguousarray(x, dtype=float) for x in (trial.gyr, trial.acc, trial.mag))
    out = VQF(1.0 / trial.rate_hz).updateBatch(gyr, acc, mag if use_mag else None)
    return out["quat9D"] if use_mag else out["quat6D"]


def run_fusion(trial: Trial) -> np.ndarray:
    imufusion = _require("imufusion", "imufusion")

    settings = imufusion.AhrsSettings()  # its constructor ignores keywords: set the fields
    settings.sample_rate = trial.rate_hz
    settings.convention = imufusion.CONVENTION_ENU
    settings.gain = 0.5
    settings.acceleration_rejection = 10.0
    settings.magnetic_rejection = 10.0
    settings.rejection_timeout = 5.0 * trial.rate_hz  # samples
    ahrs = imufusion.Ahrs()
    ahrs.set_settings(settings)
    gyr_dps = np.degrees(trial.gyr).astype(float)
    acc_g = (trial.acc / 9.81).astype(float)
    mag = trial.mag.astype(float)
    q = np.empty((len(gyr_dps), 4))
    for i in range(len(gyr_dps)):
        ahrs.update(gyr_dps[i], acc_g[i], mag[i])
        q[i] = ahrs.get_quaternion()
    return q


RUNNERS: dict[str, Callable[[Trial], np.ndarray]] = {
    "ours 9D": lambda t: run_ours(t, True),
    "ours 6D": lambda t: run_ours(t, False),
    "VQF 9D": lambda t: run_vqf(t, True),
    "VQF 6D": lambda t: run_vqf(t, False),
    "Fusion 9D": run_fusion,
}


def evaluate(trials: list[Trial], methods: Iterable[str] | None = None) -> dict[str, dict[str, tuple[float, ...]]]:
    """Per trial number, per method: (total, heading, inclination) RMSE in degrees."""
    methods = list(METHODS if methods is None else methods)
    unknown = [m for m in methods if m not in RUNNERS]
    if unknown:
        raise InputError(f"unknown method(s) {', '.join(map(repr, unknown))}: choose from {', '.join(map(repr, METHODS))}")
    rows: dict[str, dict[str, tuple[float, ...]]] = {}
    for trial in trials:
        rows[trial.number] = {m: errors(RUNNERS[m](trial), trial, remove_heading=m.endswith("6D")) for m in methods}
    return rows


def summarise(rows: dict[str, dict[str, tuple[float, ...]]], numbers: Iterable[str]) -> dict[str, dict]:
    """Means over the undisturbed and the disturbed trials among `numbers`."""
    numbers = [n for n in numbers if n in rows]
    groups = {"undisturbed": [n for n in numbers if int(n) < 20], "disturbed": [n for n in numbers if int(n) >= 20]}
    summary: dict[str, dict] = {}
    for group, members in groups.items():
        if not members:
            continue
        methods = rows[members[0]].keys()
        summary[group] = {"trials": members,
                          **{m: tuple(float(np.mean([rows[n][m][k] for n in members])) for k in range(3))
                             for m in methods}}
    return summary


def markdown(rows: dict[str, dict[str, tuple[float, ...]]], per_trial: bool = True) -> str:
    """The tables: held-out and all trials (or the trials given), then one row per trial."""
    out = []
    sets = [("the held-out trials", HELD_OUT), ("all 18 trials", tuple(rows))]
    if set(rows) != set(TUNING + HELD_OUT):
        sets = [("the trials given", tuple(rows))]
    methods = list(next(iter(rows.values())))
    for title, numbers in sets:
        summary = summarise(rows, numbers)
        columns = [g for g in ("undisturbed", "disturbed") if g in summary]
        head = " | ".join(f"{g} ({len(summary[g]['trials'])})" for g in columns)
        out += [f"RMSE in degrees, total / heading / inclination, mean over {title}:", "",
                f"| filter | {head} |", "|---|" + "---|" * len(columns)]
        for m in methods:
            cells = " | ".join(" / ".join(f"{v:.2f}" for v in summary[g][m]) for g in columns)
            out.append(f"| {m} | {cells} |")
        out.append("")
    if per_trial:
        out += ["Per trial (total / heading / inclination):", "",
                "| trial | split | " + " | ".join(methods) + " |", "|---|---|" + "---|" * len(methods)]
        for number, by_method in rows.items():
            split = "tuning" if number in TUNING else "held-out"
            out.append(f"| {number} | {split} | " + " | ".join(" / ".join(f"{v:.2f}" for v in by_method[m])
                                                            for m in methods) + " |")
        out.append("")
    return "\n".join(out)


def figures(methods: Iterable[str] = ("ours 9D", "ours 6D")) -> dict[str, dict[str, dict[str, list[float]]]]:
    """For a benchmark line: per split (held-out, all), group and method, the mean
    [total, heading, inclination] RMSE in degrees, rounded to 0.001."""
    rows = evaluate(load(), methods)
    out: dict[str, dict[str, dict[str, list[float]]]] = {}
    for split, numbers in (("held_out", HELD_OUT), ("all", tuple(rows))):
        summary = summarise(rows, numbers)
        out[split] = {group: {m: [round(v, 3) for v in summary[group][m]] for m in methods} for group in summary}
    return out
