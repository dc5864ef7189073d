"""A simulated take as the studio's messages, and as the host's input path delivers them:
what `mocap eval` solves and calibrates from, so that the evaluation scores the frames mocapd
would solve (keypoints rounded to the wire's float32, frames grouped and IMUs mapped by the
host's C++ input path) rather than the simulator's arrays.

Each frame of every camera is captured at the take's told time and arrives then, its subject
the one person it sends (none on the frames the detector skipped: HS mode). The IMUs are
sampled on the camera trigger: one sample per sensor at each frame's told time, holding the
reading of the frame's true time, in one batch sent then — the synchroniser hands each frame
exactly its readings. (IMUs on their own clock would be interpolated to the frames: a
different experiment, whose resampling alone raises the velocity errors by 8-11%.)
"""

from __future__ import annotations

import dataclasses

import numpy as np

from mocap import _core
from mocap.model import frames as host_frames
from mocap.net import wire
from mocap.sim.take import Take

START_NS = 1_000_000_000  # frame 0's capture time: told times may be slightly negative
HUB = "sim"


def messages(t: Take) -> list[tuple[int, str, bytes]]:
    """(arrival ns, type name, payload) of the take's camera frames and IMU batches, in
    arrival order (a frame's cameras, then its batch)."""
    out = []
    for f, time_ns in enumerate(frame_times_ns(t)):
        for c, cam in enumerate(t.rig.cameras):
            persons = None if t.keypoints[f] is None else [t.keypoints[f][c]]
            out.append((time_ns, host_frames.camera_frame(cam, f, time_ns, t.layout.name, persons)))
        if t.imus:
            out.append((time_ns, _batch(t, f, time_ns)))
    return [wire.arrived(arrival, m) for arrival, m in out]


def scene_messages(scene, suits: bool = False) -> list[tuple[int, str, bytes]]:
    """(arrival ns, type name, payload) of a scene of several performers (mocap.sim.people):
    each camera's frame with every person it found, in its own order; suits: then each
    performer's suit's batch (hub "suitP", sensors "pP_NAME": suit_sensor)."""
    first = scene.performers[0]
    out = []
    for f, (time_ns, seen) in enumerate(zip(frame_times_ns(first), scene.persons)):
        for c, cam in enumerate(first.rig.cameras):
            persons = None if seen is None else seen[c]
            out.append(wire.arrived(time_ns, host_frames.camera_frame(cam, f, time_ns, first.layout.name, persons)))
        for p, t in enumerate(scene.performers if suits else []):
            batch = _batch(t, f, time_ns)
            batch.hub_id = f"suit{p}"
            for s in batch.samples:
                s.sensor_id = suit_sensor(p, s.sensor_id)
            out.append(wire.arrived(time_ns, batch))
    return out


def suit_sensor(performer: int, name: str) -> str:
    """The name of `performer`'s suit's sensor `name` in a session of several people."""
    return f"p{performer}_{name}"


def suit_of_sensor(sensor: str) -> int:
    """The performer whose suit a sensor named by suit_sensor is in."""
    prefix, _, _ = sensor.partition("_")
    if not (prefix.startswith("p") and prefix[1:].isdigit()):
        raise ValueError(f"{sensor!r} is not a suit's sensor (pN_NAME)")
    return int(prefix[1:])


def frame_times_ns(t: Take) -> list[int]:
    return [START_NS + int(round(s * 1e9)) for s in t.times]


def _batch(t: Take, f: int, time_ns: int) -> wire.ImuBatch:
    batch = wire.ImuBatch(hub_id=HUB, sequence=f, send_time_ns=time_ns)
    for s, q, a in zip(t.imus, t.quaternions[f], t.accelerations[f]):
        batch.samples.add(sensor_id=s.name, sample_time_ns=time_ns, qw=q[0], qx=q[1], qy=q[2], qz=q[3],
                          ax=a[0], ay=a[1], az=a[2], packet_counter=f % 65536)
    return batch


def delivered(t: Take) -> tuple[Take, list]:
    """The take as the host's input path delivers it (keypoints, readings and times of its
    synchronised frames; the truth unchanged), and those frames (_core.SyncedFrame).
    RuntimeError when the path did not deliver every frame whole: the simulated studio has
    no late or lost input, so that is a fault of the simulator or of the path."""
    path = _core.InputPath(t.rig, t.imus, t.layout, _core.SyncOptions(), _core.SolverOptions().min_confidence)
    frames = host_frames.synchronise_all(path, messages(t), frame_times_ns(t))
    cams, k, m = len(t.rig.cameras), len(t.layout), len(t.imus)
    keypoints, quats, accs = [], np.full((len(frames), m, 4), np.nan), np.full((len(frames), m, 3), np.nan)
    for i, frame in enumerate(frames):
        if frame.cameras_detected:
            kp = np.zeros((cams, k, 3))
            if frame.cameras:  # none: the subject was seen by no camera
                kp[frame.cameras] = frame.keypoints
            keypoints.append(kp)
        else:
            keypoints.append(None)
        quats[i, frame.imus], accs[i, frame.imus] = frame.quaternions_wxyz, frame.accelerations
    times = (np.array([f.time_ns for f in frames]) - START_NS) * 1e-9
    return dataclasses.replace(t, times=times, keypoints=keypoints, quaternions=quats, accelerations=accs), frames
