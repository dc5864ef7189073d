"""PCA pose prior over the non-root DOF (slide "Pose prior terms").

Training (`mocap train-prior`): every frame of every clip, retargeted to the canonical
skeleton (retarget.py), resampled to the capture rate; k-means over the 60 non-root DOF
so that common poses (standing, walking) do not dominate; PCA of the cluster centres,
keeping 95% of their variance (the paper went from 60 to 23 dimensions).
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np

from mocap import _core, paths
from mocap.errors import InputError
from mocap.io import retarget

log = logging.getLogger(__name__)

DEFAULT = paths.HOST_DATA / "prior_default.json"
SPLIT = paths.HOST_DATA / "motion_split.json"


def kmeans(x: np.ndarray, k: int, iterations: int = 50, seed: int = 0) -> np.ndarray:
    """(k, d) cluster centres of the rows of x: k-means++ seeding, then Lloyd's iterations."""
    rng = np.random.default_rng(seed)
    k = min(k, len(x))
    centres = [x[rng.integers(len(x))]]
    d2 = ((x - centres[0]) ** 2).sum(axis=1)
    for _ in range(1, k):
        centres.append(x[rng.choice(len(x), p=d2 / d2.sum())] if d2.sum() > 0 else x[rng.integers(len(x))])
        d2 = np.minimum(d2, ((x - centres[-1]) ** 2).sum(axis=1))
    c = np.array(centres)
    for _ in range(iterations):
        dist = (x**2).sum(1)[:, None] - 2 * x @ c.T + (c**2).sum(1)[None, :]
        label = dist.argmin(axis=1)
        moved = np.array([x[label == j].mean(axis=0) if (label == j).any() else c[j] for j in range(k)])
        if np.allclose(moved, c):
            break
        c = moved
    return c


def fit(poses: np.ndarray, variance: float = 0.95, clusters: int | None = 500, seed: int = 0) -> _core.PosePrior:
    """PCA of (N, 66) poses' non-root DOF (of k-means centres when clusters is set)."""
    bar = np.asarray(poses, dtype=float)[:, 6:]
    if clusters:
        bar = kmeans(bar, clusters, seed=seed)
    mean = bar.mean(axis=0)
    _, s, vt = np.linalg.svd(bar - mean, full_matrices=False)
    var = s**2 / max(len(bar) - 1, 1)
    k = min(int(np.searchsorted(np.cumsum(var) / var.sum(), variance) + 1), bar.shape[1] - 1)
    return _core.PosePrior(mean, vt[:k].T.copy(), np.sqrt(np.maximum(var[:k], 1e-12)))


def test_clips(split: Path = SPLIT) -> set[str]:
    """Clips (paths relative to the mocap data folder) scored in docs/results.md."""
    return set(json.loads(split.read_text())["test"])


def validation_clips(split: Path = SPLIT) -> set[str]:
    """Clips where solver settings are tuned: neither trained on nor scored."""
    return set(json.loads(split.read_text()).get("validation", []))


def held_out_clips(split: Path = SPLIT) -> set[str]:
    """Clips kept out of training: the test and the validation clips."""
    return test_clips(split) | validation_clips(split)


def train(folder: Path, rate: float = 60.0, exclude: set[str] = frozenset(), **fit_args) -> tuple[_core.PosePrior, dict]:
    """The prior of every BVH file under folder whose relative path is not excluded."""
    files = sorted(p for p in Path(folder).rglob("*.bvh") if p.relative_to(folder).as_posix() not in exclude)
    if not files:
        raise InputError(f"no training clips under {folder}")
    poses = [retarget.load_clip(p, rate)[1] for p in files]
    frames = sum(len(p) for p in poses)
    prior = fit(np.concatenate(poses), **fit_args)
    info = {"clips": [p.relative_to(folder).as_posix() for p in files], "frames": frames,
            "rank": int(prior.basis.shape[1]), "rate_hz": rate}
    log.info("prior from %d clips, %d frames: rank %d", len(files), frames, info["rank"])
    return prior, info


def save(prior: _core.PosePrior, path: Path, info: dict | None = None) -> None:
    data = json.loads(prior.to_json())
    if info:
        data["training"] = info
    Path(path).write_text(json.dumps(data, separators=(",", ":")) + "\n")


def load(path: Path = DEFAULT) -> _core.PosePrior:
    return _core.PosePrior.load(str(path))
