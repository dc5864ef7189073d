"""Accuracy metrics of solved poses against the truth (`mocap eval`, the demo, the tables).

Metrics, as the paper plus jitter: mean joint position error (cm, the 21 bone origins,
global, no alignment), mean bone orientation error (deg), mean joint velocity error
(cm/s, finite differences over the frames' true times), per joint; joint_centres_pos_cm /
_vel_cms: the same over the 13 anatomical joint centres (mocap.model.joint_centres), the fair
comparison of solves made with different skeletons (the estimated calibration's skeleton
puts the pelvis origin, spine and clavicles where its own convention does, not where the
clip's skeleton does). floor_cm is the position error left when only the systematic errors
act (site offsets and camera perturbation, no random noise), triangulated exactly: the mean
error of the joint-centre keypoints' DLT triangulation against the true joints.
"""

from __future__ import annotations

import numpy as np

from mocap import _core, rotations
from mocap.calibration.window import Calibration
from mocap.model import joint_centres, studio
from mocap.sim.take import Take


UPSIDE_DOWN_DEG = 90.0


def errors(skeleton: _core.Skeleton, truth: np.ndarray, solved: np.ndarray, dt: float,
           solved_skeleton: _core.Skeleton | None = None) -> dict:
    """Errors of solved poses against the truth; solved_skeleton: the skeleton they were solved
    with, when it is not the true one (estimated calibration)."""
    fk_s = [(solved_skeleton or skeleton).forward_kinematics(th) for th in solved]
    return transform_errors(skeleton, truth, np.array([p for _, p in fk_s]), np.array([r for r, _ in fk_s]), dt)


def transform_errors(skeleton: _core.Skeleton, truth: np.ndarray, p_s: np.ndarray, r_s: np.ndarray,
                     dt: float) -> dict:
    """errors() of solved bone positions p_s (F, J, 3) and orientations r_s (F, J, 3, 3), as
    the host publishes them (PoseFrame.joints: whatever skeleton each frame was solved with)."""
    fk_t = [skeleton.forward_kinematics(th) for th in truth]
    p_t, r_t = np.array([p for _, p in fk_t]), np.array([r for r, _ in fk_t])
    pos = np.linalg.norm(p_s - p_t, axis=-1)  # (F, J) m
    ori = np.degrees(rotations.angle_between(r_s, r_t))  # (F, J)
    ori_tracking = offset_removed_errors_deg(r_s, r_t)  # (F, J)
    vel = np.linalg.norm(np.diff(p_s, axis=0) - np.diff(p_t, axis=0), axis=-1) / dt  # (F-1, J) m/s
    names = skeleton.bone_names
    centres = joint_centres.bone_indices(names)
    return {"pos_error_cm": 100 * float(pos.mean()), "ori_error_deg": float(ori.mean()),
            "ori_error_offset_removed_deg": float(ori_tracking.mean()),
            "vel_error_cms": 100 * float(vel.mean()),
            "joint_centres_pos_cm": 100 * float(pos[:, centres].mean()),
            "joint_centres_vel_cms": 100 * float(vel[:, centres].mean()),
            "per_joint": {n: {"pos_cm": 100 * float(pos[:, j].mean()), "ori_deg": float(ori[:, j].mean()),
                              "ori_offset_removed_deg": float(ori_tracking[:, j].mean())}
                          for j, n in enumerate(names)},
            # frames on which a bone is more than a quarter turn from the truth, with any
            # skeleton convention's offset: upside down, reversed (the offset-removed metric
            # takes a bone upside down all take for a constant offset)
            "upside_down_frames": {n: int(k) for n, k in zip(names, (ori > UPSIDE_DOWN_DEG).sum(axis=0)) if k},
            "pos_error_cm_per_frame": (100 * pos.mean(axis=1)).round(3).tolist()}


def offset_removed_errors_deg(r_s: np.ndarray, r_t: np.ndarray) -> np.ndarray:
    """(F, J) degrees between solved and true bone orientations (F, J, 3, 3) once each bone's
    constant offset over the take is taken out (R_t ~ R_s D_j, D_j the chordal mean of
    R_s^T R_t): two skeletons that put a bone's frame differently at rest (an estimated
    calibration's, another tool's) differ by such a constant; what remains is tracking error."""
    d = np.swapaxes(r_s, -1, -2) @ r_t  # (F, J, 3, 3)
    u, _, vt = np.linalg.svd(d.sum(axis=0))  # per bone
    flip = np.ones(u.shape[:-1])
    flip[:, -1] = np.sign(np.linalg.det(u @ vt))
    mean = (u * flip[:, None, :]) @ vt  # (J, 3, 3), the nearest rotation to the mean
    return np.degrees(rotations.angle_between(mean[None], d))


def _triangulate(rig: _core.Rig, views: list[tuple[int, np.ndarray]]) -> np.ndarray:
    rows = []
    for c, px in views:
        cam = rig.cameras[c]
        u, v = cam.undistort(px[None])[0]
        p = np.hstack([cam.rotation, cam.translation[:, None]])
        rows += [u * p[2] - p[0], v * p[2] - p[1]]
    x = np.linalg.svd(np.array(rows))[2][-1]
    return x[:3] / x[3]


def floor_cm(t: Take) -> float:
    """Systematic errors alone, triangulated exactly from every camera that sees the point."""
    centres = np.flatnonzero(np.linalg.norm(t.layout.offsets, axis=1) < 1e-9)  # joint-centre keypoints
    errs = []
    for theta in t.thetas[:: max(1, len(t.thetas) // 60)]:
        _, pos = t.skeleton.forward_kinematics(theta)
        points = studio.site_positions(t.skeleton, t.layout.bones, t.detector_sites, theta)
        for k in centres:
            views = []
            for c, cam in enumerate(t.true_rig.cameras):
                px, ok = cam.project(points[k][None])
                if ok[0] and 0 <= px[0, 0] < cam.width and 0 <= px[0, 1] < cam.height:
                    views.append((c, px[0]))
            if len(views) >= 2:
                errs.append(np.linalg.norm(_triangulate(t.rig, views) - pos[t.layout.bones[k]]))
    return 100 * float(np.mean(errs)) if errs else float("nan")


LIMB_BONES = ["shin_l", "shin_r", "foot_l", "foot_r", "forearm_l", "forearm_r", "hand_l", "hand_r"]  # their lengths


def _bone_axis(skeleton: _core.Skeleton, bone: int) -> np.ndarray:
    """Unit direction to the bone's first child away from its origin (bone frame); z for none."""
    offsets = np.asarray(skeleton.offsets)
    child = next((c for c, p in enumerate(skeleton.parents) if p == bone and np.linalg.norm(offsets[c]) > 1e-6), None)
    axis = offsets[child] if child is not None else np.array([0.0, 0.0, 1.0])
    return axis / np.linalg.norm(axis)


def calibration_errors(t: Take, c: Calibration) -> dict:
    """Estimated against true, per IMU: heading (deg), mounting (deg; in full, and the bone
    axis' direction in the sensor frame: what video observes of it), position (cm); the limb
    lengths (cm); per keypoint the site (cm), estimated and the layout's."""
    out = {}
    for est, true in zip(c.imus, t.imus):
        turn = np.asarray(est.reference) @ np.asarray(true.reference).T
        axis = _bone_axis(t.skeleton, true.bone)
        along = np.clip(np.dot(np.asarray(est.mount).T @ axis, np.asarray(true.mount).T @ axis), -1.0, 1.0)
        out[true.name] = {"heading_deg": float(np.degrees(abs(np.arctan2(turn[1, 0], turn[0, 0])))),
                          "mount_deg": float(np.degrees(rotations.angle_between(np.asarray(est.mount),
                                                                                 np.asarray(true.mount)))),
                          "mount_axis_deg": float(np.degrees(np.arccos(along))),
                          "offset_cm": 100 * float(np.linalg.norm(np.asarray(est.offset) - np.asarray(true.offset)))}
    names = t.skeleton.bone_names
    lengths = {b: 100 * float(np.linalg.norm(c.skeleton.offsets[names.index(b)]) -
                              np.linalg.norm(t.skeleton.offsets[names.index(b)])) for b in LIMB_BONES}
    # Keypoint sites (cm, per keypoint): the estimate's and the layout's distance from where
    # the detector's keypoints really sit (each in its bone's frame).
    # "observed": the same along the directions the window observed (c.site_directions), the
    # part of each error the calibration could remove.
    true_sites = np.asarray(t.detector_sites)
    estimated, nominal = np.asarray(c.layout.offsets) - true_sites, np.asarray(t.layout.offsets) - true_sites
    d = c.site_directions if c.site_directions.size else np.zeros((estimated.size, 0))
    along = lambda e: (d @ (d.T @ e.reshape(-1))).reshape(-1, 3)  # noqa: E731
    sites = {n: {"estimated_cm": 100 * float(np.linalg.norm(e)), "layout_cm": 100 * float(np.linalg.norm(e0)),
                 "observed_estimated_cm": 100 * float(np.linalg.norm(oe)),
                 "observed_layout_cm": 100 * float(np.linalg.norm(oe0))}
             for n, e, e0, oe, oe0 in zip(t.layout.names, estimated, nominal, along(estimated), along(nominal))}
    return {"imus": out, "limb_length_cm": lengths, "sites": sites}


def heading_errors_deg(t: Take, c, tracked: np.ndarray) -> np.ndarray:
    """(F, M) |heading error| per frame and IMU (deg): the reference in use, Rz(psi_f) times the
    estimated one (tracked: (F, M) corrections psi_f, rad), against the one that would
    explain the frame's reading exactly: the true reference turned by the reading's own
    heading error (its drift and spec error), which the truth's poses and mountings reveal.
    c: anything with the IMU sites in use as `imus` (a Calibration, or the take)."""
    measured = rotations.matrix_from_quaternion(t.quaternions)  # sensor -> own reference
    out = np.empty(tracked.shape)
    for f, theta in enumerate(t.thetas):
        rot, _ = t.skeleton.forward_kinematics(theta)
        for i, (est, true) in enumerate(zip(c.imus, t.imus)):
            sensor = np.asarray(rot[true.bone]) @ np.asarray(true.mount)  # true world orientation
            wanted = sensor @ measured[f, i].T  # reference -> world that explains the reading
            turn = rotations.exp(np.array([0.0, 0.0, tracked[f, i]])) @ np.asarray(est.reference) @ wanted.T
            out[f, i] = abs(np.degrees(2 * np.arctan2(rotations.quaternion_from_matrix(turn)[3],
                                                      rotations.quaternion_from_matrix(turn)[0])))
    return np.where(out > 180.0, 360.0 - out, out)
