"""`mocap bench --only peer`: our per-frame solve against Pose2Sim's triangulation, on
Pose2Sim's real Balancing trial (mocap.io.demo_data.fetch_trial: 4 cameras, OpenPose
BODY_25B detections, its calibration, video only), both timed on one core in one run.

Ours: the trial as a take folder (mocap.eval.balancing_take) calibrated from its own
messages as `mocap solve --take` calibrates it (mocap.takes.solve.calibrate), then the
messages fed through the host's input path (mocap.model.frames.input_path; the subject
chosen by the solver's tracked pose, as mocapd chooses it) and each synchronised frame solved
by a Solver made from the calibrated session. Timed: each `Solver.solve` call (validation,
warm start, Levenberg-Marquardt, the monitors, the pybind11 call); untimed: the messages'
decoding and synchronisation. Also reported: the solver's own `solve_time_ms` (inside C++,
what mocapd publishes in PoseFrame).

Both sides are timed in wall time (`median_ms`, `p90_ms`, `speedup_wall_*`) and in the
process's CPU time (`cpu_*`): on a shared machine another process preempting the timed one
adds its time slice to the wall time of the frames it falls in, not to the CPU time. That
biases the wall-time ratio of medians towards the shorter side: few of our frames are hit,
most of Pose2Sim's are. On an idle core the two agree. Each side runs `repeats` times; the run with the
lowest median is kept.

Pose2Sim: its own code (`pose2sim==0.10.49` from PyPI) in its own virtual environment,
made on first use under .cache/ from peer_requirements.txt, run by pose2sim_driver.py (which
says what of it is timed) in a subprocess on the same core, with the very keypoints each of
our solves got. The subprocess dies with this process (PR_SET_PDEATHSIG).
"""

from __future__ import annotations

import dataclasses
import fcntl
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from mocap import _core, paths, processes
from mocap.eval import balancing_take
from mocap.io.demo_data import fetch_trial
from mocap.io.session import Session
from mocap.model import frames, prior
from mocap.model.solver import Solver
from mocap.takes import solve as take_solve

HERE = Path(__file__).parent
REQUIREMENTS = HERE / "peer_requirements.txt"
DRIVER = HERE / "pose2sim_driver.py"
VERSION = "0.10.49"
VENV = paths.REPO / ".cache" / f"peer-pose2sim-{VERSION}"
KEYPOINTS = 25  # OpenPose BODY_25B, the take's layout
TARGET = 20.0  # the product's criterion: our median per-frame solve this many times faster
SINGLE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
                 "NUMEXPR_NUM_THREADS": "1", "VECLIB_MAXIMUM_THREADS": "1", "MPLBACKEND": "Agg"}


class PeerUnavailable(Exception):
    """Pose2Sim's side cannot run here (its environment cannot be made, or it failed)."""


def _run(command: list[str], timeout: float, core: int | None = None, what: str = "") -> str:
    """Runs a subprocess tied to this one; its stdout, or PeerUnavailable with its last words."""
    env = {**os.environ, **SINGLE_THREAD}
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout, env=env,
                              preexec_fn=processes.die_with_parent(core), stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        raise PeerUnavailable(f"{what} did not finish in {timeout:.0f} s") from None
    except OSError as e:
        raise PeerUnavailable(f"{what} could not start: {e}") from None
    if done.returncode != 0:
        lines = [line for line in (done.stderr or done.stdout).splitlines() if line.strip()]
        raise PeerUnavailable(f"{what} failed (exit {done.returncode}): {' | '.join(lines[-3:])}")
    return done.stdout


def _interpreter() -> str:
    """The Python the project's .venv was made from (Debian's: pose2sim wants >= 3.11)."""
    base = getattr(sys, "_base_executable", "") or sys.executable
    return base if Path(base).is_file() else "/usr/bin/python3"


def environment(venv: Path = VENV, requirements: Path = REQUIREMENTS, timeout: float = 1200.0) -> Path:
    """The Python of Pose2Sim's virtual environment, made from `requirements` (pip, no other
    dependency) unless it was made from the same file before; PeerUnavailable when it cannot
    be made (no network, no such release)."""
    stamp = hashlib.sha256(requirements.read_bytes()).hexdigest()
    python, marker = venv / "bin" / "python", venv / ".complete"
    venv.parent.mkdir(parents=True, exist_ok=True)
    with open(venv.parent / f".{venv.name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # one maker at a time
        if marker.is_file() and marker.read_text() == stamp and python.is_file():
            return python
        shutil.rmtree(venv, ignore_errors=True)
        what = f"making Pose2Sim's environment in {venv}"
        _run([_interpreter(), "-m", "venv", str(venv)], 120, what=what)
        _run([str(python), "-m", "pip", "install", "-q", "--disable-pip-version-check", "--no-deps",
              "--retries", "1", "--timeout", "20", "-r", str(requirements)], timeout, what=what)
        marker.write_text(stamp)
    return python


def pose2sim(keypoints: np.ndarray, calibration: Path, repeats: int = 3, core: int | None = None,
             check: bool = True, python: Path | None = None) -> dict:
    """Pose2Sim's triangulation timed per frame on keypoints (F, C, 25, 3) (NaN: the camera
    has no subject) by pose2sim_driver.py in Pose2Sim's environment, pinned to `core`."""
    python = python or environment()
    with tempfile.TemporaryDirectory() as folder:
        np.savez(Path(folder) / "frames.npz", keypoints=keypoints)
        out = Path(folder) / "result.json"
        command = [str(python), str(DRIVER), "--frames", str(Path(folder) / "frames.npz"), "--calib",
                   str(calibration), "--out", str(out), "--repeats", str(repeats)] + (["--check"] if check else [])
        _run(command, 600, core, what="Pose2Sim's triangulation (pose2sim_driver.py)")
        return json.loads(out.read_text())


@dataclasses.dataclass
class Solved:
    wall_ms: float  # the Solver.solve call, timed from Python
    cpu_ms: float  # this process's CPU time in it (what preemption by other processes does not add)
    solve_time_ms: float  # the solver's own timing (C++)
    iterations: int
    status: str
    theta: np.ndarray
    keypoints: np.ndarray  # (4, 25, 3) the frame's keypoints per camera of the rig (NaN: no subject)


def solver_of(session: Path) -> Solver:
    """A Solver of the session's files and options, as mocapd makes it."""
    s = Session.load(session)
    skeleton = _core.Skeleton.load(str(s.file("skeleton")))
    rig = _core.Rig.load(str(s.file("rig")))
    layout = _core.KeypointLayout.load(str(s.file("layout")), skeleton)
    imus = _core.load_imu_sites(str(s.file("imus")), skeleton)
    pose_prior = None if s.file("prior") is None else prior.load(s.file("prior"))
    return Solver(skeleton, rig, layout, imus, pose_prior, s.solver_options())


def solve_timed(session: Path, messages: list, n_cameras: int, limit: int | None = None) -> list[Solved]:
    """The messages' frames as mocapd solves them, each solve timed; the first `limit` only."""
    solver, path = solver_of(session), frames.input_path(session)
    out: list[Solved] = []

    def solve(ready: list) -> None:
        for f in ready:
            if limit is not None and len(out) >= limit:
                return
            args = (f.timestamp, f.cameras, f.keypoints, f.imus, f.quaternions_wxyz, f.accelerations)
            start, cpu = time.perf_counter_ns(), time.process_time_ns()
            r = solver.solve(*args)
            wall, cpu = (time.perf_counter_ns() - start) * 1e-6, (time.process_time_ns() - cpu) * 1e-6
            per_camera = np.full((n_cameras, KEYPOINTS, 3), np.nan)
            per_camera[list(f.cameras)] = args[2]
            out.append(Solved(wall, cpu, r.solve_time_ms, r.iterations, r.status, np.array(r.theta), per_camera))

    for arrival_ns, type_name, payload in messages:
        if type_name in frames.INPUT_TYPES:
            path.feed(type_name, payload, arrival_ns, solver)
            solve(path.take_ready(arrival_ns))
    solve(path.flush())
    return out


def statistics(ms) -> dict:
    """Per-frame median, 90th percentile, mean and maximum (ms)."""
    ms = np.asarray(ms, dtype=float)
    return {"frames": int(len(ms)), "median_ms": round(float(np.median(ms)), 4),
            "p90_ms": round(float(np.percentile(ms, 90)), 4), "mean_ms": round(float(ms.mean()), 4),
            "max_ms": round(float(ms.max()), 4)}


def best_of(runs: list) -> tuple[dict, list[float]]:
    """The statistics of the run with the lowest median (shared machines are noisy), and
    every run's median."""
    stats = [statistics(r) for r in runs]
    return min(stats, key=lambda s: s["median_ms"]), [s["median_ms"] for s in stats]


def timings(wall_runs: list, cpu_runs: list) -> dict:
    """One side's figures: the wall-time statistics of its fastest run, every run's median,
    and the CPU-time median and p90 of its fastest run by CPU time."""
    best, medians = best_of(wall_runs)
    cpu, _ = best_of(cpu_runs)
    return {**best, "medians_ms_of_repeats": medians, "cpu_median_ms": cpu["median_ms"], "cpu_p90_ms": cpu["p90_ms"]}


def ours(calibrated: take_solve.Calibrated, repeats: int, limit: int | None = None) -> tuple[dict, np.ndarray]:
    """Our side: statistics of the fastest of `repeats` runs, and the frames' keypoints (F, 4, 25, 3)."""
    n_cameras = len(calibrated.take.rig.cameras)
    runs = [solve_timed(calibrated.session, calibrated.messages, n_cameras, limit) for _ in range(repeats)]
    figures = timings([[s.wall_ms for s in run] for run in runs], [[s.cpu_ms for s in run] for run in runs])
    inside, _ = best_of([[s.solve_time_ms for s in run] for run in runs])
    statuses = [s.status for s in runs[0]]
    return ({**figures, "solve_time_ms_median": inside["median_ms"], "solve_time_ms_p90": inside["p90_ms"],
             "mean_iterations": round(float(np.mean([s.iterations for s in runs[0]])), 2),
             "statuses": {s: statuses.count(s) for s in sorted(set(statuses))}},
            np.array([s.keypoints for s in runs[0]]))


def theirs(result: dict) -> dict:
    """Pose2Sim's side from the driver's result: statistics of its fastest run and what it did."""
    kept = {k: v for k, v in result.items() if k not in ("per_frame_ms", "per_frame_cpu_ms", "frames")}
    return {**timings(result["per_frame_ms"], result["per_frame_cpu_ms"]), **kept}


def measure(calibrated: take_solve.Calibrated, calibration: Path, repeats: int = 3, limit: int | None = None,
            check: bool = True, python: Path | None = None) -> dict:
    """The bench line of a calibrated take (its first `limit` frames); Pose2Sim's side skipped
    (with the reason) when it cannot run here. Pose2Sim runs on this process's first core."""
    core = min(os.sched_getaffinity(0))
    line: dict = {"bench": "peer", "take": "Pose2Sim Balancing trial (4 cameras, OpenPose BODY_25B, video only)"}
    line["ours"], keypoints = ours(calibrated, repeats, limit)
    try:
        line["pose2sim"] = theirs(pose2sim(keypoints, calibration, repeats, core, check, python))
    except PeerUnavailable as e:
        return {**line, "skipped": f"Pose2Sim's side: {e}", "cpu_affinity": sorted(os.sched_getaffinity(0))}
    for name, key in (("wall_median", "median"), ("wall_p90", "p90"), ("cpu_median", "cpu_median"),
                      ("cpu_p90", "cpu_p90")):
        line[f"speedup_{name}"] = round(line["pose2sim"][f"{key}_ms"] / line["ours"][f"{key}_ms"], 2)
    line["target_speedup"] = TARGET
    line["cpu_affinity"] = sorted(os.sched_getaffinity(0))
    return line


def bench(repeats: int = 3) -> dict:
    """`mocap bench --only peer`: the whole trial. DataMissingError when it is not in .cache/
    and cannot be fetched."""
    trial = fetch_trial()
    with tempfile.TemporaryDirectory() as folder:
        take = balancing_take.write(trial, Path(folder) / "take")
        calibrated = take_solve.calibrate(take, Path(folder) / "out")
        return measure(calibrated, trial / "Calib_qualisys.toml", repeats)
