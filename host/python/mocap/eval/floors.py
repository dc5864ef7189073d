"""What a simulated take's measurements themselves tell of each bone's orientation, whatever a
solver makes of them (`mocap eval --floors`, and a table of docs/results.md).

- A bone with a sensor: the sensor's own error, its reading taken through its true mounting and
  reference against the true bone (the simulated MTw's spec error, drift and soft-tissue wobble).
- A bone without one: its orientation fitted to one frame's detections of the keypoints it
  moves (its own, and those of the bones beyond it, shifted with it), every other bone's world
  orientation and the root at the truth, started at the truth: Levenberg-Marquardt on the
  solver's E_P (Cauchy at 5 px, confidence-weighted). A direction no keypoint observes (a toe's roll, a
  neck's or a clavicle's twist) stays at the truth, so the figure is a floor: no per-frame solve
  from these detections does better without a prior that knows the answer. Frames with fewer
  than MIN_DETECTIONS detections of those keypoints are counted apart: there only a prior or the
  motion can say anything.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mocap import rotations
from mocap.sim.take import Config, Take, simulate

PIXEL_SCALE = 5.0  # px: E_P's Cauchy scale (SolverOptions.position, 1 / 25 with loss scale 1)
MIN_CONFIDENCE = 0.05  # SolverOptions.min_confidence
ITERATIONS = 10
MIN_DETECTIONS = 3  # fewer: the frame counts as unobserved (one stray detection would be fitted exactly)
DAMPING = 1e-3  # keeps an unobserved direction where it started (observed ones: ~1e2 per detection)


def sensor_errors(t: Take) -> dict[str, float]:
    """Mean degrees between each sensor's reading and its bone's truth, per sensed bone."""
    names = t.skeleton.bone_names
    truth = np.array([t.skeleton.forward_kinematics(th)[0] for th in t.thetas])  # (F, J, 3, 3)
    measured = rotations.matrix_from_quaternion(t.quaternions)  # (F, M, 3, 3)
    out = {}
    for m, site in enumerate(t.imus):
        e = rotations.angle_between(truth[:, site.bone] @ np.asarray(site.mount), np.asarray(site.reference) @ measured[:, m])
        out[names[site.bone]] = float(np.degrees(np.nanmean(e)))
    return out


def _subtree_shifts(parents: np.ndarray, offsets: np.ndarray, j: int, bones: np.ndarray) -> np.ndarray:
    """(K, 3) for each keypoint on a bone beyond j: the offset (in j's frame) of the child of j
    it hangs from, which turning j swings; NaN for the others (those on j: the caller's)."""
    child_of = {}
    for b in range(len(parents)):
        path = [b]
        while parents[path[-1]] >= 0 and path[-1] != j:
            path.append(parents[path[-1]])
        if path[-1] == j and b != j:
            child_of[b] = path[-2]
    out = np.full((len(bones), 3), np.nan)
    for k, b in enumerate(bones):
        if b in child_of:
            out[k] = offsets[child_of[b]]
    return out


def _fit(rig, truth_points, r_j, lever, detections) -> tuple[np.ndarray, int]:
    """Rotation vector (bone frame) of bone j that best explains one frame's detections
    (C, K, 3), and the number of detections used (0: fewer than MIN_DETECTIONS)."""
    cams = [(c, np.flatnonzero(detections[c, :, 2] > MIN_CONFIDENCE)) for c in range(len(rig.cameras))]
    cams = [(c, ks) for c, ks in cams if len(ks)]
    used = sum(len(ks) for _, ks in cams)
    if used < MIN_DETECTIONS:
        return np.zeros(3), 0

    def residuals(w):
        moved = r_j @ rotations.exp(w) - r_j
        points = truth_points + np.einsum("ij,kj->ki", moved, lever)  # on j: p_j + R' o; beyond: + (R' - R) offset
        out = []
        for c, ks in cams:
            px, _ = rig.cameras[c].project(points[ks])
            out.append(px - detections[c, ks, :2])
        return np.concatenate(out)

    confidence = np.concatenate([detections[c, ks, 2] for c, ks in cams])

    def cost(r):  # E_P: confidence x Cauchy of the squared pixel error in PIXEL_SCALE units
        return float((confidence * np.log1p((r**2).sum(axis=1) / PIXEL_SCALE**2)).sum())

    w, r, damping = np.zeros(3), residuals(np.zeros(3)), DAMPING
    for _ in range(ITERATIONS):
        weight = np.repeat(confidence / (1 + (r**2).sum(axis=1) / PIXEL_SCALE**2), 2)
        jac = np.stack([(residuals(w + h) - r).ravel() / 1e-6 for h in np.eye(3) * 1e-6], axis=1)
        normal = jac.T @ (weight[:, None] * jac)
        step = np.linalg.solve(normal + damping * (np.eye(3) + np.diag(np.diag(normal))), -jac.T @ (weight * r.ravel()))
        tried = residuals(w + step)
        if cost(tried) < cost(r):
            w, r, damping = w + step, tried, max(damping / 10, DAMPING)
        else:
            damping *= 10
        if np.linalg.norm(step) < 1e-7:
            break
    return w, used


def keypoint_floors(t: Take, bones: list[str], sites: np.ndarray | None = None, stride: int = 5) -> dict[str, dict]:
    """Per bone: the single-frame fit's mean and median error (deg) over the frames (every
    `stride`-th) with MIN_DETECTIONS of the keypoints it moves, and the share of frames with
    fewer. Every other bone is held at the truth: a floor for a bone whose neighbours carry
    sensors (the 13-IMU set); a chain of bones without any is not estimated jointly. sites: the
    keypoints' offsets on their bones the fit assumes (default: the layout's nominal ones, as
    the oracle solve knows them; t.detector_sites: a calibration that found them exactly)."""
    names, parents = t.skeleton.bone_names, np.asarray(t.skeleton.parents)
    offsets, kp_bones = np.asarray(t.skeleton.offsets), np.asarray(t.layout.bones)
    kp_offsets = np.asarray(t.layout.offsets if sites is None else sites)
    out = {}
    for name in bones:
        j = names.index(name)
        beyond = _subtree_shifts(parents, offsets, j, kp_bones)
        on_j = kp_bones == j
        lever = np.where(on_j[:, None], kp_offsets, beyond)
        moved = np.isfinite(lever).all(axis=1)
        errors, unobserved = [], 0
        for f in range(0, len(t.thetas), stride):
            frame = t.keypoints[f]
            rots, pos = t.skeleton.forward_kinematics(t.thetas[f])
            if frame is None:
                continue
            points = pos[kp_bones] + np.einsum("kij,kj->ki", rots[kp_bones], kp_offsets)
            detections = frame[:, moved]
            w, used = _fit(t.true_rig, points[moved], rots[j], lever[moved], detections)
            if used:
                errors.append(np.degrees(np.linalg.norm(w)))
            else:
                unobserved += 1
        e = np.array(errors) if errors else np.array([np.nan])
        out[name] = {"floor_deg": float(np.mean(e)), "floor_median_deg": float(np.median(e)),
                     "unobserved_pct": 100.0 * unobserved / max(unobserved + len(errors), 1)}
    return out


def evaluate(clip: Path, config: Config, seed: int) -> dict:
    """The sensors' own errors and the keypoint floors (nominal and true sites) of the bones
    without a sensor, on the take `mocap eval` simulates from the same clip, config and seed."""
    t = simulate(clip, config, np.random.default_rng(seed))
    sensed = sensor_errors(t)
    bones = [n for n in t.skeleton.bone_names if n not in sensed]
    nominal, true_sites = keypoint_floors(t, bones), keypoint_floors(t, bones, t.detector_sites)
    return {"clip": str(clip), "sensors_deg": sensed,
            "floors": {n: {**nominal[n], "floor_true_sites_deg": true_sites[n]["floor_deg"]} for n in bones}}
