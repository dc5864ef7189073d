"""A simulated take: a real motion (a BVH clip, or poses in memory such as
mocap.sim.demo_motion's) played in front of simulated cameras and IMUs.

Presets as the paper: HQ detects on every frame with 8 cameras; HS on 2 consecutive
frames of every 8 with 4 cameras; with the 13- or 6-IMU set. Cameras: positions on a
ring of 4.5 m radius around the clip's mean position (8 positions 45 degrees apart,
1.0 or 2.5 m high), 1920x1080, f = 1400 px, radial distortion (studio.ring_rig). The solver is told a perturbed rig (0.2 deg and 5 mm of
extrinsic error per camera) and frame times with 1 ms of jitter; it is given the true
skeleton and sensor mounting ("oracle" calibration). IMU mounting rotations are drawn
up to 20 deg.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from mocap import _core, paths, rotations
from mocap.io import retarget
from mocap.model import studio
from mocap.sim import detector, extremes, imu, occlusion


@dataclasses.dataclass(frozen=True)
class Preset:
    imus: str  # "13" or "6"
    cameras: int
    period: int  # detections on `burst` consecutive frames of every `period`
    burst: int


PRESETS = {"hq13": Preset("13", 8, 1, 1), "hs13": Preset("13", 4, 8, 2),
           "hq6": Preset("6", 8, 1, 1), "hs6": Preset("6", 4, 8, 2)}


@dataclasses.dataclass(frozen=True)
class Config:
    preset: str = "hq13"
    cameras: int | None = None  # overrides the preset's
    layout: str = "blazepose33"
    rate: float = 60.0  # Hz
    detector: detector.DetectorErrors = detector.DetectorErrors()
    imu: imu.ImuErrors = imu.ImuErrors()
    detect_every: tuple[int, int] | None = None  # (period, burst): overrides the preset's
    camera_rotation_deg: float = 0.2
    camera_shift_m: float = 0.005
    time_jitter_s: float = 0.001
    mount_max_deg: float = 20.0
    bends: tuple[extremes.Bend, ...] = ()  # joints bent beyond the clip (the truth includes them)
    slips: tuple[extremes.Slip, ...] = ()  # sensors that slip on their segment mid-take
    cameras_lost_at_s: float | None = None  # every camera stops detecting from then on (IMUs only)


@dataclasses.dataclass
class Take:
    skeleton: _core.Skeleton
    layout: _core.KeypointLayout  # nominal sites, as the solver knows them
    imus: list  # IMU sites with their true mounting (oracle)
    rig: _core.Rig  # what the solver is told
    true_rig: _core.Rig
    thetas: np.ndarray  # (F, 66) truth
    times: np.ndarray  # (F,) told frame times, s
    keypoints: list  # per frame: (C, K, 3) or None (no detections this frame)
    quaternions: np.ndarray  # (F, M, 4) w, x, y, z
    accelerations: np.ndarray  # (F, M, 3) sensor frame
    detector_sites: np.ndarray  # (K, 3) true site offsets (nominal + systematic)
    calibration: str = "oracle"


def camera_positions(n: int) -> list[int]:
    """Which of the 8 ring positions (45 degrees apart) n cameras take: spread evenly, except
    that two cameras stand 90 degrees apart (opposite cameras cannot triangulate along
    their common axis)."""
    if not 1 <= n <= 8:
        raise ValueError(f"1 to 8 cameras, not {n}")
    return [0, 2] if n == 2 else sorted({round(i * 8 / n) % 8 for i in range(n)})


def camera_rig(n: int, thetas: np.ndarray, radius: float = 4.5) -> _core.Rig:
    """n cameras round the motion's centre: up to 8 on the 8 positions of camera_positions,
    more (a stage's dozens) evenly on a ring of their own, alternately low and high."""
    ring = lambda cameras: studio.ring_rig(cameras, center=thetas[:, :2].mean(axis=0), radius=radius,  # noqa: E731
                                           heights=(1.0, 2.5))
    if n > 8:
        return ring(n)
    return _core.Rig([ring(8).cameras[i] for i in camera_positions(n)])


def perturbed_rig(rig: _core.Rig, degrees: float, metres: float, rng) -> _core.Rig:
    cams = []
    for cam in rig.cameras:
        axis, shift = rng.normal(size=3), rng.normal(size=3)
        centre = cam.center() + metres * shift / np.linalg.norm(shift)
        cam.rotation = rotations.exp(np.radians(degrees) * axis / np.linalg.norm(axis)) @ cam.rotation
        cam.translation = -cam.rotation @ centre
        cams.append(cam)
    return _core.Rig(cams)


def preset_of(config: Config) -> Preset:
    preset = PRESETS[config.preset]
    if config.detect_every:
        preset = dataclasses.replace(preset, period=config.detect_every[0], burst=config.detect_every[1])
    return preset


def performer(skeleton: _core.Skeleton, config: Config, rng) -> tuple[_core.KeypointLayout, np.ndarray, list]:
    """What a performer brings: the keypoint layout on their skeleton, where the detector
    finds each keypoint on them (the layout's sites plus a systematic offset drawn per
    performer), and their suit (the preset's IMU set, each sensor mounted at a random turn of
    up to config.mount_max_deg)."""
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / f"{config.layout}.json"), skeleton).scaled_to(skeleton)
    sites = layout.offsets + detector.site_offsets(len(layout), config.detector, rng)
    imus = _core.load_imu_sites(str(paths.IMU_SETS[preset_of(config).imus]), skeleton)
    for s in imus:
        axis = rng.normal(size=3)
        s.mount = rotations.exp(axis / np.linalg.norm(axis) * np.radians(rng.uniform(0, config.mount_max_deg)))
    return layout, sites, imus


def frame_times(n: int, dt: float, config: Config, rng) -> tuple[np.ndarray, np.ndarray]:
    """The true frame times and those the cameras report (config.time_jitter_s, increasing)."""
    true_times = np.arange(n) * dt
    times = true_times + rng.normal(scale=config.time_jitter_s, size=n)
    return true_times, np.maximum.accumulate(np.maximum(times, true_times - 0.4 * dt))


def simulate(clip: Path, config: Config, rng: np.random.Generator) -> Take:
    """A take of a BVH clip, resampled at config.rate."""
    mapping, thetas, dt = retarget.load_clip(clip, config.rate)
    skeleton = _core.Skeleton.from_bones(retarget.BONES, mapping.parents, mapping.offsets)
    return simulate_motion(skeleton, thetas, dt, config, rng)


def simulate_motion(skeleton: _core.Skeleton, thetas: np.ndarray, dt: float, config: Config,
                    rng: np.random.Generator) -> Take:
    """A take of a motion in memory: (F, 66) poses of `skeleton`, dt apart (config.rate unused),
    with config's bends and slips."""
    for b in config.bends:
        thetas = extremes.bend(thetas, skeleton.bone_names, b, dt)
    preset = preset_of(config)
    layout, sites, imus = performer(skeleton, config, rng)
    true_rig = camera_rig(config.cameras or preset.cameras, thetas)
    told_rig = perturbed_rig(camera_rig(config.cameras or preset.cameras, thetas), config.camera_rotation_deg,
                             config.camera_shift_m, rng)
    true_times, times = frame_times(len(thetas), dt, config, rng)
    keypoints = _detections(skeleton, layout, sites, true_rig, thetas, preset, config, rng)
    if config.cameras_lost_at_s is not None:
        keypoints = [None if at >= config.cameras_lost_at_s else k for k, at in zip(keypoints, true_times)]
    quats, accs = imu_readings(skeleton, imus, thetas, true_times, config, rng)
    for slip in config.slips:
        quats, accs = extremes.slip(quats, accs, [s.name for s in imus], true_times, slip)
    return Take(skeleton, layout, imus, told_rig, true_rig, thetas, times, keypoints, quats, accs, sites)


def _detections(skeleton, layout, sites, rig, thetas, preset: Preset, config: Config, rng) -> list:
    names, parents = skeleton.bone_names, skeleton.parents
    caps = occlusion.capsules(names, parents)
    twins = detector.mirror(layout.names)
    centres = np.array([c.center() for c in rig.cameras])
    out = []
    for f, theta in enumerate(thetas):
        if f % preset.period >= preset.burst:
            out.append(None)
            continue
        rot, pos = skeleton.forward_kinematics(theta)
        points = studio.site_positions(skeleton, layout.bones, sites, theta)
        hidden = occlusion.hidden(centres, points, np.asarray(layout.bones), rot, pos, caps, parents)
        frame = np.zeros((len(rig.cameras), len(layout), 3))
        for c, cam in enumerate(rig.cameras):
            px, ok = cam.project(points)
            frame[c] = detector.detect(np.nan_to_num(px), ok & ~hidden[c], twins, (cam.width, cam.height),
                                       config.detector, rng)
        out.append(frame)
    return out


def imu_readings(skeleton, imus, thetas, times, config: Config, rng):
    """The IMUs' readings of poses at `times` with config.imu's errors: quaternions (F, M, 4)
    w, x, y, z and accelerations (F, M, 3) in the sensor frames."""
    sensor_world, accel = studio.sensor_motion(skeleton, imus, thetas, times)
    parents, offsets = skeleton.parents, skeleton.offsets
    axis = np.zeros(accel.shape)  # each sensor's bone direction, towards the bone's first child
    for i, s in enumerate(imus):
        child = next((b for b, p in enumerate(parents) if p == s.bone), None)
        along = offsets[child] / max(np.linalg.norm(offsets[child]), 1e-9) if child is not None else np.array([0, 0, 1.0])
        axis[:, i] = sensor_world[:, i] @ s.mount.T @ along  # bone frame -> world
    measured, accel_sensor = imu.corrupt(sensor_world, accel, axis, times, config.imu, rng)
    quats, _ = studio.readings(imus, measured, accel)
    return quats, accel_sensor
