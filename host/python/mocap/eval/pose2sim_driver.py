"""Pose2Sim's own triangulation, timed per frame. Run by the Python of Pose2Sim's virtual
environment (mocap.eval.peer makes it under .cache/), never imported by the project's .venv:
it imports Pose2Sim and nothing of mocap.

Input: an .npz with `keypoints` (F, C, 25, 3): x, y (px), likelihood of the OpenPose
BODY_25B keypoints of each frame and camera (NaN where the camera has no subject), and the
calibration (Pose2Sim's Calib.toml format). Output: a JSON file (see `main`).

What is timed per frame is what Pose2Sim's `triangulation.triangulate_all` does with a frame
once its JSON files are read (`extract_files_frame_f`, file I/O, not timed): the likelihood
threshold (keypoints below `likelihood_threshold_triangulation` become NaN) and, for every
keypoint of its BODY_25B model, its `triangulation_from_best_cameras` (likelihood-weighted
DLT of every camera subset, reprojection error, cameras excluded one more at a time until
the error is under `reproj_error_threshold_triangulation`). Its configuration is the
Demo_SinglePerson Config.toml shipped in the package, with the project folder, the model
(BODY_25B) and the frame rate (60) set. Not timed: reading the files, and the passes over
the whole take once every frame is triangulated (gap interpolation, trimming, TRC writing):
they need the frames after the current one, so they are offline. `--check` also runs
`triangulate_all` itself once on the same frames written as OpenPose JSON files and reports
the largest difference between its TRC and the per-frame results (0 but rounding when the
per-frame calls are the ones Pose2Sim makes) and its wall time, I/O and all.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import tempfile
import time
from importlib.metadata import version
from pathlib import Path

logging.disable(logging.WARNING)  # Pose2Sim's import probes for a GUI and warns when there is none
import cv2  # noqa: E402
import numpy as np  # noqa: E402
import rtoml  # noqa: E402
from anytree import RenderTree  # noqa: E402
from Pose2Sim import common, skeletons, triangulation  # noqa: E402

MODEL = "BODY_25B"


def config(project: Path) -> dict:
    """Pose2Sim's demo configuration (Demo_SinglePerson/Config.toml) for this trial."""
    demo = Path(triangulation.__file__).parent / "Demo_SinglePerson" / "Config.toml"
    cfg = rtoml.load(demo)
    cfg["project"].update(project_dir=str(project), frame_rate=60, multi_person=False)
    cfg["pose"]["pose_model"] = MODEL
    if cfg["triangulation"].get("undistort_points") or cfg["triangulation"].get("handle_LR_swap"):
        raise SystemExit("the demo configuration undistorts or swaps sides: this driver does not time that")
    return cfg


def model() -> tuple[list[int], list[str], list[int]]:
    """Pose2Sim's BODY_25B keypoints in its order: OpenPose indices, names, and for each the
    index of its left/right counterpart (itself when it has none)."""
    nodes = [node for _, _, node in RenderTree(getattr(skeletons, MODEL)) if node.id is not None]
    names = [n.name for n in nodes]
    other = {"L": "R", "R": "L"}
    swapped = [names.index(other[n[0]] + n[1:]) if n[0] in other and other[n[0]] + n[1:] in names else i
               for i, n in enumerate(names)]
    return [n.id for n in nodes], names, swapped


def triangulate_frame(cfg: dict, x, y, likelihood, swapped, projections, calib) -> tuple:
    """One frame as triangulate_all treats it: x, y, likelihood (C, K) are modified. Returns
    points (K, 3) (NaN where not triangulated), reprojection errors (K,) px and cameras
    excluded (K,)."""
    with np.errstate(invalid="ignore"):
        low = likelihood < cfg["triangulation"]["likelihood_threshold_triangulation"]
    x[low], y[low], likelihood[low] = np.nan, np.nan, np.nan
    points, errors, excluded = [], [], []
    for k in range(x.shape[1]):
        kpt = np.array((x[:, k], y[:, k], likelihood[:, k]))
        s = swapped[k]
        kpt_swapped = np.array((x[:, s], y[:, s], likelihood[:, s]))
        q, error, n_excluded, _ = triangulation.triangulation_from_best_cameras(cfg, kpt, kpt_swapped, projections,
                                                                                calib)
        points.append(q)
        errors.append(error)
        excluded.append(n_excluded)
    return np.array(points, dtype=float), np.array(errors, dtype=float), np.array(excluded)


def timed_runs(cfg: dict, frames: np.ndarray, calib_file: Path, repeats: int) -> tuple[list, list, np.ndarray, dict]:
    """Per-frame milliseconds of each repeat (wall, and this process's CPU time), the points
    of the last and its summary."""
    ids, _, swapped = model()
    projections = common.computeP(calib_file, undistort=False)
    calib = common.retrieve_calib_params(calib_file)
    selected = frames[:, :, ids, :]  # (F, C, K, 3) in Pose2Sim's order, as extract_files_frame_f reads them
    runs, cpu_runs = [], []
    for _ in range(repeats):
        copies = [(f[..., 0].copy(), f[..., 1].copy(), f[..., 2].copy()) for f in selected]
        ms, cpu_ms, points, errors, excluded = [], [], [], [], []
        for x, y, lik in copies:
            start, cpu = time.perf_counter_ns(), time.process_time_ns()
            q, e, n = triangulate_frame(cfg, x, y, lik, swapped, projections, calib)
            ms.append((time.perf_counter_ns() - start) * 1e-6)
            cpu_ms.append((time.process_time_ns() - cpu) * 1e-6)
            points.append(q)
            errors.append(e)
            excluded.append(n)
        runs.append(ms)
        cpu_runs.append(cpu_ms)
    errors = np.array(errors)
    summary = {"points_triangulated": int(np.isfinite(np.array(points)[..., 0]).sum()),
               "points": int(errors.size), "mean_reprojection_error_px": float(np.nanmean(errors)),
               "mean_cameras_excluded": float(np.mean(excluded))}
    return runs, cpu_runs, np.array(points), summary


def write_project(cfg: dict, frames: np.ndarray, calib_file: Path) -> Path:
    """A Pose2Sim trial folder of the frames: Config.toml, calibration/, pose/camN_json/*.json
    (one person per file, none where the camera has no subject)."""
    project = Path(cfg["project"]["project_dir"])
    (project / "calibration").mkdir(parents=True)
    (project / "calibration" / calib_file.name).write_bytes(calib_file.read_bytes())
    (project / "Config.toml").write_text(rtoml.dumps(cfg))
    for c in range(frames.shape[1]):
        folder_c = project / "pose" / f"cam{c + 1}_json"
        folder_c.mkdir(parents=True)
        for f, person in enumerate(frames[:, c]):
            people = [] if np.isnan(person).all() else [{"pose_keypoints_2d": person.reshape(-1).tolist()}]
            (folder_c / f"cam{c + 1:02d}.{f:04d}.json").write_text(json.dumps({"people": people}))
    return project


def read_trc(path: Path, n_keypoints: int) -> tuple[np.ndarray, np.ndarray]:
    """Frame numbers and (F, K, 3) points of a TRC written by Pose2Sim, back in Z-up (its
    zup2yup writes each point as (Y, Z, X))."""
    rows = [line.split("\t") for line in path.read_text().splitlines()[5:] if line.strip()]
    frames = np.array([int(float(r[0])) for r in rows])
    yup = np.array([[float(v) for v in r[2:2 + 3 * n_keypoints]] for r in rows]).reshape(len(rows), n_keypoints, 3)
    return frames, yup[..., [2, 0, 1]]


def check(cfg: dict, frames: np.ndarray, calib_file: Path, points: np.ndarray) -> dict:
    """triangulate_all on the same frames (files and all): its wall time, and the largest
    distance between its TRC and the per-frame points where those were triangulated."""
    project = write_project(cfg, frames, calib_file)
    start = time.perf_counter()
    triangulation.triangulate_all(cfg)
    seconds = time.perf_counter() - start
    trc = next((project / "pose-3d").glob("*.trc"))
    trc_frames, trc_points = read_trc(trc, points.shape[1])
    ours = points[trc_frames]
    finite = np.isfinite(ours).all(axis=-1)
    distance = np.linalg.norm(trc_points[finite] - ours[finite], axis=-1)
    return {"seconds": seconds, "ms_per_frame": 1e3 * seconds / len(frames), "trc_frames": int(len(trc_frames)),
            "points_compared": int(finite.sum()),
            "max_difference_mm": 1e3 * float(distance.max()) if distance.size else None}


def main(argv: list[str] | None = None) -> int:
    a = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    a.add_argument("--frames", required=True, help=".npz with keypoints (F, C, 25, 3)")
    a.add_argument("--calib", required=True, help="calibration, Pose2Sim's .toml format")
    a.add_argument("--out", required=True, help="JSON file to write")
    a.add_argument("--repeats", type=int, default=3)
    a.add_argument("--check", action="store_true", help="also run triangulate_all once and compare")
    args = a.parse_args(argv)
    cv2.setNumThreads(1)
    frames = np.load(args.frames)["keypoints"]
    calib_file = Path(args.calib)
    with tempfile.TemporaryDirectory() as folder:
        cfg = config(Path(folder) / "trial")
        runs, cpu_runs, points, summary = timed_runs(cfg, frames, calib_file, args.repeats)
        result = {"pose2sim": version("pose2sim"), "numpy": np.__version__, "opencv": cv2.__version__,
                  "python": sys.version.split()[0], "cpu_affinity": sorted(os.sched_getaffinity(0)),
                  "frames": int(len(frames)), "keypoints": int(points.shape[1]), "per_frame_ms": runs,
                  "per_frame_cpu_ms": cpu_runs,
                  "timed": "likelihood threshold + triangulation_from_best_cameras per keypoint", **summary}
        if args.check:
            result["triangulate_all"] = check(cfg, frames, calib_file, points)
    Path(args.out).write_text(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
