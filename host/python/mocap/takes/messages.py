"""A take folder as the studio's messages: what its cameras' boxes and an IMU hub would have
sent, with the times they would have reached the host, so that a take is calibrated and
solved by the live host's own input path (mocap.calibration.from_messages,
mocap.recording.offline) — the same subject choice, frame grouping and IMU interpolation
as mocapd's.

Frame f of every camera is captured at start + f / frame_rate and arrives then, with every
person of its pose file (the host chooses the subject). Each IMU sample is sent when it is
taken (a hub without delay); the synchroniser waits for the sample after a frame for up to
two IMU periods, so no frame is released without it. Samples more than IMU_MARGIN_S outside the video are left out: they would clock frames
without cameras. A take is also a session (`write_session`): the rig, the default skeleton,
the layout and the take's sensors (uncalibrated), for the calibration to fill in.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from mocap import _core, paths
from mocap.io.session import Session, SyncSettings
from mocap.io.take_folder import TakeFolder
from mocap.model import frames
from mocap.model.solver import imu_set_json
from mocap.net import wire

IMU_MARGIN_S = 0.1  # IMU samples kept before the first and after the last video frame
HUB = "take"


def start_ns(take: TakeFolder) -> int:
    """The capture time of frame 0: 1 s, or later when the IMUs start earlier (times are >= 0)."""
    first = min([m.times_s[0] for m in take.imus if len(m.times_s)] + [0.0])
    return int(np.ceil(max(0.0, IMU_MARGIN_S - first) + 1.0)) * 1_000_000_000


def frame_time_ns(take: TakeFolder, frame: int | np.ndarray) -> int | np.ndarray:
    """Capture time of video frame `frame` (start_ns + frame / frame_rate)."""
    return start_ns(take) + np.round(np.asarray(frame) * 1e9 / take.frame_rate).astype(np.int64)


def messages(take: TakeFolder) -> list[tuple[int, str, bytes]]:
    """(arrival ns, type name, payload) of the take's camera frames and IMU batches, in
    arrival order (cameras before the hub at one time)."""
    out = [(arrival, 0, m) for arrival, m in _camera_frames(take)]
    out += [(arrival, 1, m) for arrival, m in _imu_batches(take)]
    out.sort(key=lambda m: (m[0], m[1]))
    return [wire.arrived(arrival, m) for arrival, _, m in out]


def _camera_frames(take: TakeFolder):
    times = frame_time_ns(take, np.arange(take.n_frames))
    for camera, people in zip(take.rig.cameras, take.people):
        for f, persons in enumerate(people):
            yield int(times[f]), frames.camera_frame(camera, f, int(times[f]), take.layout, list(persons))


def _imu_batches(take: TakeFolder):
    """Every sample inside the video (+- IMU_MARGIN_S), each sent when it is taken: one batch
    per sample time. A quaternion or acceleration that is not finite is flagged invalid (and
    sent as zeros)."""
    origin = start_ns(take)
    lo, hi = -IMU_MARGIN_S, (take.n_frames - 1) / take.frame_rate + IMU_MARGIN_S
    samples = []
    for m in take.imus:
        keep = (m.times_s >= lo) & (m.times_s <= hi)
        counters = m.packets if m.packets is not None else np.arange(len(m.times_s))
        for t, q, a, n in zip(m.times_s[keep], m.quaternions[keep], m.accelerations[keep], counters[keep]):
            samples.append((origin + int(round(t * 1e9)), m.sensor, q, a, int(n) % 65536))
    samples.sort(key=lambda s: s[0])
    batch = None
    for sample in samples:
        if batch is None or sample[0] != batch.send_time_ns:
            if batch is not None:
                yield batch.send_time_ns, batch
            batch = wire.ImuBatch(hub_id=HUB, sequence=0 if batch is None else batch.sequence + 1,
                                  send_time_ns=sample[0])
        batch.samples.add(**_sample(*sample))
    if batch is not None:
        yield batch.send_time_ns, batch


def _sample(time_ns: int, sensor: str, q: np.ndarray, a: np.ndarray, counter: int) -> dict:
    status = 0
    if not np.isfinite(q).all():
        status, q = status | wire.ImuSample.STATUS_ORIENTATION_INVALID, np.zeros(4)
    if not np.isfinite(a).all():
        status, a = status | wire.ImuSample.STATUS_ACCELERATION_INVALID, np.zeros(3)
    return dict(sensor_id=sensor, sample_time_ns=time_ns, qw=q[0], qx=q[1], qy=q[2], qz=q[3],
                ax=a[0], ay=a[1], az=a[2], packet_counter=counter, status=status)


def write_session(take: TakeFolder, folder: Path) -> Path:
    """The take's session in `folder` (session.json, rig.json, skeleton.json, imus.json): the
    default skeleton, the take's layout and sensors on their bones (uncalibrated), frames
    grouped within a quarter of the frame period (the default 4 ms would merge frames above
    125 fps), a frame waited for (and IMUs interpolated across) up to two IMU periods. Its inputs and output name no
    endpoint: it is for solving the take's messages offline."""
    folder.mkdir(parents=True, exist_ok=True)
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    sites = []
    for m in take.imus:
        site = _core.ImuSite()
        site.name, site.bone = m.sensor, skeleton.bone_names.index(m.bone)
        sites.append(site)
    (folder / "skeleton.json").write_text(skeleton.to_json())
    (folder / "rig.json").write_text(take.rig.to_json())
    (folder / "imus.json").write_text(json.dumps(imu_set_json(skeleton, sites), indent=1))
    period_ms = 1000.0 / take.imu_rate if take.imus else 0.0
    sync = SyncSettings(group_tolerance_ms=min(4.0, 250.0 / take.frame_rate),
                        max_wait_ms=max(25.0, 2 * period_ms), imu_max_gap_ms=max(40.0, 2 * period_ms))
    session = Session("skeleton.json", "rig.json", str(paths.LAYOUTS / f"{take.layout}.json"), "imus.json",
                      ["take"], "take", prior=str(paths.HOST_DATA / "prior_default.json"), sync=sync, base=folder)
    return session.save(folder / "session.json")
