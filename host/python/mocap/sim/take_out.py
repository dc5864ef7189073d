"""The simulated studio written as a take folder (`mocap simulate --take-out DIR`), with the
truth that a take from another tool would not carry, for the calibration's tests.

The demo motion (mocap.sim.demo_motion, 60 Hz), or a BVH clip (retargeted, its first
`seconds`), is played through mocap.sim.take with the chosen keypoint layout: the told
(perturbed) rig goes to Calib.toml, each camera's detections to OpenPose JSON (a camera that
sees no keypoint in a frame, and every frame without detections, writes "people": []), and
the IMUs are sampled at IMU_RATE on the take's clock (sample k at k / IMU_RATE s, video
frame f at f / 60 s). Each IMU reports its orientation in its own earth frame: the world
turned about Z by a random heading psi (uniform in [-180, 180) degrees, one per sensor),
    q_file = Rz(psi)^T R_world<-sensor,   so   R_world<-sensor = Rz(psi) q_file.

Truth, beside the take's files (the reader never opens them): truth.json (per sensor
heading_deg, mount as a rotation vector sensor -> bone frame, offset in metres in the bone
frame; the detector's true keypoint sites), truth_skeleton.json, truth_thetas.npy
((F, 66) poses at the video frames) and truth_rig.json (the unperturbed cameras).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from mocap import _core, rotations
from mocap.io import retarget
from mocap.io.take_folder import SEGMENT_BONES, ImuRecording, TakeFolder, write_take
from mocap.io.xsens_csv import TICKS_PER_S
from mocap.model.poses import calibration_poses
from mocap.sim import demo_motion, imu
from mocap.sim import take as sim_take

FRAME_RATE = 60.0  # Hz
IMU_RATE = 100.0  # Hz: 100 SampleTimeFine ticks per sample
BONE_SEGMENTS = {bone: segment for segment, bone in SEGMENT_BONES.items()}


@dataclasses.dataclass
class Truth:
    skeleton: _core.Skeleton
    thetas: np.ndarray  # (F, 66) at video frame f / FRAME_RATE
    imus: list  # _core.ImuSite: true mount and offset; reference = Rz(heading)
    headings_deg: np.ndarray  # (M,)
    true_rig: _core.Rig
    layout: _core.KeypointLayout
    keypoint_sites: np.ndarray  # (K, 3) m, in each keypoint's bone frame


def _people(keypoints: list, n_cameras: int, n_keypoints: int) -> list:
    """[camera][frame] (P, K, 3) of the simulation's per-frame (C, K, 3) or None."""
    none = np.zeros((0, n_keypoints, 3))
    return [[none if k is None or not (k[c, :, 2] > 0).any() else k[c][None] for k in keypoints]
            for c in range(n_cameras)]


def _motion(seconds: float, clip: Path | None) -> tuple[_core.Skeleton, np.ndarray, float]:
    """(skeleton, poses, dt) at FRAME_RATE: the demo motion, or the clip's first `seconds`."""
    if clip is None:
        return demo_motion.load_motion(FRAME_RATE, seconds)
    mapping, thetas, dt = retarget.load_clip(clip, FRAME_RATE)
    skeleton = _core.Skeleton.from_bones(retarget.BONES, mapping.parents, mapping.offsets)
    return skeleton, thetas[: int(round(seconds / dt)) + 1], dt


def simulate(seconds: float, preset: str = "hq13", seed: int = 0,
             imu_errors: imu.ImuErrors = imu.ImuErrors(),
             calibration_pose: str | None = None, still_s: float = 0.0,
             motion: Path | None = None, layout: str = "blazepose33") -> tuple[TakeFolder, Truth]:
    """The take (IMU quaternions in each sensor's earth frame) and its truth; with a
    calibration pose ("T" or "N", mocap.model.poses), the performer holds it for 1 s
    and blends into the motion over 0.5 s first; with still_s, stands still first for that
    long (in a pose of the motion, 3 s in) and blends into it over 0.5 s. motion: a BVH clip
    instead of the demo motion; layout: the detector's keypoint layout (host/data/layouts)."""
    rng = np.random.default_rng(seed)
    skeleton, thetas, dt = _motion(seconds, motion)
    if still_s > 0:
        thetas = demo_motion.after_held_pose(thetas, thetas[min(len(thetas) - 1, round(3.0 / dt))], dt, still_s)
    if calibration_pose:
        thetas = demo_motion.after_held_pose(thetas, calibration_poses(skeleton)[calibration_pose], dt)
    config = sim_take.Config(preset=preset, imu=imu_errors, layout=layout)
    t = sim_take.simulate_motion(skeleton, thetas, dt, config, rng)
    headings = rng.uniform(-180.0, 180.0, len(t.imus))
    for s, h in zip(t.imus, headings):
        s.reference = rotations.exp(np.array([0.0, 0.0, np.radians(h)]))
    n = int(np.floor((len(thetas) - 1) * dt * IMU_RATE + 1e-9)) + 1
    times = np.arange(n) * round(TICKS_PER_S / IMU_RATE) / TICKS_PER_S  # whole SampleTimeFine ticks, as read
    quats, accs = sim_take.imu_readings(skeleton, t.imus, demo_motion.interpolate(thetas, times / dt), times,
                                        config, rng)
    names = skeleton.bone_names
    imus = [ImuRecording(s.name, BONE_SEGMENTS[names[s.bone]], names[s.bone], times, quats[:, i], accs[:, i])
            for i, s in enumerate(t.imus)]
    take = TakeFolder(FRAME_RATE, len(thetas), "Z", t.rig, t.layout.name,
                      _people(t.keypoints, len(t.rig.cameras), len(t.layout)), imus, IMU_RATE)
    return take, Truth(skeleton, thetas, t.imus, headings, t.true_rig, t.layout, t.detector_sites)


def write_truth(folder: Path, truth: Truth) -> None:
    names = truth.skeleton.bone_names
    (folder / "truth_skeleton.json").write_text(truth.skeleton.to_json())
    (folder / "truth_rig.json").write_text(truth.true_rig.to_json())
    np.save(folder / "truth_thetas.npy", truth.thetas)
    sensors = {s.name: {"segment": BONE_SEGMENTS[names[s.bone]], "bone": names[s.bone], "heading_deg": float(h),
                        "mount": rotations.log(np.asarray(s.mount)).tolist(), "offset": np.asarray(s.offset).tolist()}
               for s, h in zip(truth.imus, truth.headings_deg)}
    sites = [{"name": n, "bone": names[b], "offset": np.asarray(o).tolist()}
             for n, b, o in zip(truth.layout.names, truth.layout.bones, truth.keypoint_sites)]
    (folder / "truth.json").write_text(json.dumps({
        "format": "mocap.take_truth/1",
        "conventions": "R_world<-sensor = Rz(heading_deg) @ quaternion in the IMU file = R_world<-bone @ exp(mount); "
                       "sensor site = bone origin + R_world<-bone @ offset (m); thetas at video frame f / frame_rate",
        "frame_rate": FRAME_RATE, "skeleton": "truth_skeleton.json", "thetas": "truth_thetas.npy",
        "rig": "truth_rig.json", "sensors": sensors, "keypoint_sites": sites}, indent=1) + "\n")


def run(folder: Path, seconds: float, preset: str = "hq13", seed: int = 0,
        calibration_pose: str | None = None, still_s: float = 0.0, motion: Path | None = None,
        layout: str = "blazepose33") -> dict:
    """`mocap simulate --take-out`: simulates, writes the take folder and its truth."""
    take, truth = simulate(seconds, preset, seed, calibration_pose=calibration_pose, still_s=still_s,
                           motion=motion, layout=layout)
    write_take(folder, take)
    write_truth(Path(folder), truth)
    return {"take": str(folder), "frames": take.n_frames, "cameras": len(take.rig.cameras),
            "imus": len(take.imus), "imu_samples": len(take.imus[0].times_s) if take.imus else 0}
