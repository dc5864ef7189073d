"""The mocap.v1 wire formats on ZeroMQ: one message = two frames, [type, payload].

The type frame is the message's full protobuf name ("mocap.v1.KeypointFrame"): its
version lets a reader drop a message of another version before decoding it. The payload is
the serialised message. `decode` never raises anything but WireError, whose `reason` is the
drop counter to increment ("unknown_type", "wrong_version", "oversized", "undecodable",
"not_finite", "invalid").
"""

from __future__ import annotations

import math

from mocap.v1 import (calibration_pb2, health_pb2, imu_batch_pb2, imu_sample_pb2, keypoint_frame_pb2,
                      keypoint_person_pb2, pose_frame_pb2)

VERSION = "mocap.v1"
MAX_PAYLOAD = 1 << 20  # bytes: a frame of 10 people x 133 keypoints is ~20 kB

KeypointFrame = keypoint_frame_pb2.KeypointFrame
KeypointPerson = keypoint_person_pb2.KeypointPerson
ImuBatch = imu_batch_pb2.ImuBatch
ImuSample = imu_sample_pb2.ImuSample
PoseFrame = pose_frame_pb2.PoseFrame
Health = health_pb2.Health
Calibration = calibration_pb2.Calibration
TYPES = {cls.DESCRIPTOR.full_name: cls for cls in (KeypointFrame, ImuBatch, PoseFrame, Health, Calibration)}


class WireError(ValueError):
    def __init__(self, reason: str, detail: str):
        super().__init__(f"{reason}: {detail}")
        self.reason = reason


def encode(message) -> list[bytes]:
    return [message.DESCRIPTOR.full_name.encode(), message.SerializeToString()]


def arrived(arrival_ns: int, message) -> tuple[int, str, bytes]:
    """A message as the host's input path is fed it: (arrival ns, type name, payload)."""
    return arrival_ns, message.DESCRIPTOR.full_name, message.SerializeToString()


def decode(frames: list[bytes]):
    """The message of a two-frame ZeroMQ message, checked (see the module docstring)."""
    if len(frames) != 2:
        raise WireError("undecodable", f"{len(frames)} frames, expected 2 (type, payload)")
    type_name = bytes(frames[0]).decode("utf-8", "replace")
    cls = TYPES.get(type_name)
    if cls is None:
        package = type_name.rpartition(".")[0]
        reason = "wrong_version" if package.startswith("mocap.") and package != VERSION else "unknown_type"
        raise WireError(reason, f"message type {type_name!r}")
    if len(frames[1]) > MAX_PAYLOAD:
        raise WireError("oversized", f"{len(frames[1])} bytes > {MAX_PAYLOAD}")
    message = cls()
    try:
        message.ParseFromString(bytes(frames[1]))
    except Exception as e:  # protobuf raises DecodeError, or RuntimeWarning-style errors on garbage
        raise WireError("undecodable", f"{type_name}: {e}") from None
    _check(message)
    return message


def _finite(values, what: str) -> None:
    if not all(math.isfinite(v) for v in values):
        raise WireError("not_finite", f"{what} holds NaN or inf")


def _check(message) -> None:
    if isinstance(message, KeypointFrame):
        if not message.camera_id:
            raise WireError("invalid", "KeypointFrame without camera_id")
        for p in message.persons:
            if not len(p.x) == len(p.y) == len(p.confidence):
                raise WireError("invalid", f"{message.camera_id}: x, y, confidence of different lengths")
            _finite([*p.x, *p.y, *p.confidence], f"{message.camera_id} frame {message.frame_index}")
    elif isinstance(message, ImuBatch):
        for s in message.samples:
            if not s.sensor_id:
                raise WireError("invalid", f"{message.hub_id}: sample without sensor_id")
            _finite([s.qw, s.qx, s.qy, s.qz, s.ax, s.ay, s.az], f"{message.hub_id}/{s.sensor_id}")
    elif isinstance(message, PoseFrame):
        _finite(message.theta, "PoseFrame theta")
    elif isinstance(message, Calibration):
        if not (message.skeleton_json and message.imus_json and message.layout_json):
            raise WireError("invalid", f"Calibration from {message.source!r} without its skeleton, IMU sites or layout")
