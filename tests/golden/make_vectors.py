"""Writes the golden conformance vectors of the mocap.v1 wire formats.

Each vector is a pair: NAME.bin, the message's bytes, encoded here by a minimal
protobuf encoder that shares nothing with the generated code (so a renumbered or retyped
field breaks the vectors), and NAME.json, the expected message in protobuf's canonical
JSON mapping. Every implementation (Python: tests/test_wire_golden.py, C++:
host/daemon/wire_test.cc) must decode NAME.bin to exactly NAME.json (fields it does not
know skipped) and re-encode it to the same bytes (a relay keeps unknown fields; they were
appended last). Vectors listed in REJECTED must fail to decode. The committed files are
the contract: run this only to add vectors, and never change an existing one.

    python tests/golden/make_vectors.py
"""

from __future__ import annotations

import json
import struct
from pathlib import Path

HERE = Path(__file__).parent


def varint(n: int) -> bytes:
    n &= (1 << 64) - 1  # negative int64 are ten-byte two's complement
    out = bytearray()
    while True:
        byte, n = n & 0x7F, n >> 7
        out.append(byte | (0x80 if n else 0))
        if not n:
            return bytes(out)


def key(field: int, wire_type: int) -> bytes:
    return varint(field << 3 | wire_type)


def vint(field: int, n: int) -> bytes:  # int64, uint64, uint32, bool, enum
    return key(field, 0) + varint(n) if n else b""


def f64(field: int, x: float) -> bytes:
    return key(field, 1) + struct.pack("<d", x) if x else b""


def f32(field: int, x: float) -> bytes:
    return key(field, 5) + struct.pack("<f", x) if x else b""


def blob(field: int, data: bytes) -> bytes:
    return key(field, 2) + varint(len(data)) + data


def text(field: int, s: str) -> bytes:
    return blob(field, s.encode()) if s else b""


def packed_f32(field: int, xs: list[float]) -> bytes:
    return blob(field, b"".join(struct.pack("<f", x) for x in xs)) if xs else b""


def packed_f64(field: int, xs: list[float]) -> bytes:
    return blob(field, b"".join(struct.pack("<d", x) for x in xs)) if xs else b""


def person(p: dict) -> bytes:
    return (packed_f32(1, p["x"]) + packed_f32(2, p["y"]) + packed_f32(3, p["confidence"])
            + f32(4, p.get("score", 0)) + vint(5, p.get("trackId", 0)))


def keypoint_frame(m: dict) -> bytes:
    return (text(1, m.get("cameraId", "")) + vint(2, int(m.get("frameIndex", 0))) + vint(3, int(m.get("captureTimeNs", 0)))
            + vint(4, m.get("imageWidth", 0)) + vint(5, m.get("imageHeight", 0)) + text(6, m.get("keypointLayout", ""))
            + vint(7, int(m.get("detected", False))) + b"".join(blob(8, person(p)) for p in m.get("persons", []))
            + vint(9, int(m.get("sendTimeNs", 0))))


STATUS_BITS = {"STATUS_OK": 0, "STATUS_ORIENTATION_INVALID": 1, "STATUS_ACCELERATION_INVALID": 2,
               "STATUS_ACCELERATION_CLIPPED": 4}


def imu_sample(s: dict) -> bytes:
    return (text(1, s["sensorId"]) + vint(2, int(s.get("sampleTimeNs", 0)))
            + b"".join(f64(3 + i, s.get(c, 0.0)) for i, c in enumerate(["qw", "qx", "qy", "qz", "ax", "ay", "az"]))
            + vint(10, s.get("status", 0)) + vint(11, s.get("packetCounter", 0)))


def imu_batch(m: dict) -> bytes:
    return (text(1, m["hubId"]) + vint(2, int(m.get("sequence", 0))) + vint(3, int(m.get("sendTimeNs", 0)))
            + b"".join(blob(4, imu_sample(s)) for s in m.get("samples", [])))


def joint(j: dict) -> bytes:
    return text(1, j["name"]) + b"".join(f64(2 + i, j.get(c, 0.0)) for i, c in enumerate(["px", "py", "pz", "qw", "qx", "qy", "qz"]))


POSE_STATUS = {"STATUS_OK": 0, "STATUS_INITIALISED": 1, "STATUS_NO_OBSERVATIONS": 2, "STATUS_REJECTED_FRAME": 3,
               "STATUS_FAILED": 4}


def pose_frame(m: dict) -> bytes:
    costs = b"".join(f64(1 + i, m["costs"].get(c, 0.0))
                     for i, c in enumerate(["orientation", "position", "acceleration", "pcaProjection", "pcaDeviation"]))
    return (vint(1, int(m.get("captureTimeNs", 0))) + vint(2, int(m.get("frameIndex", 0)))
            + vint(3, POSE_STATUS[m.get("status", "STATUS_OK")]) + packed_f64(4, m.get("theta", []))
            + b"".join(blob(5, joint(j)) for j in m.get("joints", [])) + blob(6, costs)
            + vint(7, m.get("iterations", 0)) + f64(8, m.get("solveTimeMs", 0.0)) + vint(9, m.get("qualityFlags", 0))
            + b"".join(text(10, c) for c in m.get("cameras", [])) + b"".join(text(11, i) for i in m.get("imus", []))
            + f64(12, m.get("latencyMs", 0.0)) + vint(14, m.get("subjectId", 0)))


def stream_health(s: dict) -> bytes:
    return (text(1, s["stream"]) + vint(2, int(s.get("active", False))) + f64(3, s.get("rateHz", 0.0))
            + b"".join(vint(4 + i, int(s.get(c, 0))) for i, c in enumerate(["received", "dropped", "late", "duplicates",
                                                                         "malformed", "lost"]))
            + f64(10, s.get("latencyP50Ms", 0.0)) + f64(11, s.get("latencyP99Ms", 0.0))
            + vint(18, int(s.get("handshakeFailures", 0))) + vint(19, int(s.get("clockSteps", 0))))


def people(p: dict) -> bytes:
    return b"".join(vint(1 + i, int(p.get(c, 0)))
                    for i, c in enumerate(["tracked", "born", "retired", "foundAgain", "viewsDropped", "viewsUnexplained",
                                           "suitsWorn", "suitChanges", "suitsDoubted"]))


def health(m: dict) -> bytes:
    return (text(1, m["source"]) + vint(2, int(m.get("timeNs", 0))) + b"".join(blob(3, stream_health(s)) for s in m["streams"])
            + f64(4, m.get("latencyP50Ms", 0.0)) + f64(5, m.get("latencyP99Ms", 0.0))
            + vint(6, int(m.get("framesSolved", 0))) + vint(7, int(m.get("framesDropped", 0)))
            + (blob(8, people(m["people"])) if "people" in m else b""))


def calibration(m: dict) -> bytes:
    return (text(1, m.get("source", "")) + vint(2, int(m.get("sequence", 0))) + vint(3, int(m.get("validFromNs", 0)))
            + b"".join(text(4 + i, m.get(c, "")) for i, c in enumerate(["skeletonJson", "imusJson", "layoutJson",
                                                                        "reportJson"])))


KEYPOINT_FRAME = {
    "cameraId": "cam3", "frameIndex": "1152921504606846977", "captureTimeNs": "1763900000123456789",
    "imageWidth": 1920, "imageHeight": 1080, "keypointLayout": "coco17", "detected": True,
    "persons": [{"x": [512.25, 600.5, 0.0], "y": [300.75, 310.0, 0.0], "confidence": [0.875, 0.5, 0.0],
                 "score": 0.9375, "trackId": 7},
                {"x": [10.0], "y": [1079.5], "confidence": [1.0]}],
    "sendTimeNs": "1763900000130000000",
}
VECTORS = {
    "keypoint_frame": ("mocap.v1.KeypointFrame", KEYPOINT_FRAME, keypoint_frame(KEYPOINT_FRAME)),
    # A high-speed-mode frame: captured, not detected; it only clocks the solve.
    "keypoint_frame_not_detected": ("mocap.v1.KeypointFrame",
                                    {"cameraId": "cam0", "frameIndex": "8", "captureTimeNs": "-5"},
                                    keypoint_frame({"cameraId": "cam0", "frameIndex": "8", "captureTimeNs": "-5"})),
    # A newer sender's fields (numbers 99, 100): skipped by this version's readers.
    "keypoint_frame_unknown_fields": ("mocap.v1.KeypointFrame", KEYPOINT_FRAME,
                                      keypoint_frame(KEYPOINT_FRAME) + vint(99, 5) + text(100, "future")),
    "imu_batch": ("mocap.v1.ImuBatch", {
        "hubId": "hub0", "sequence": "1099511627776", "sendTimeNs": "1763900000200000000",
        "samples": [
            {"sensorId": "pelvis", "sampleTimeNs": "1763900000190000000", "qw": 0.5, "qx": -0.5, "qy": 0.5, "qz": 0.5,
             "ax": 0.125, "ay": -0.25, "az": 9.8125, "packetCounter": 65535},
            {"sensorId": "l_forearm", "sampleTimeNs": "1763900000195000000", "qw": 1.0, "ax": 160.0, "status": 6},
        ]}, None),
    "pose_frame": ("mocap.v1.PoseFrame", {
        "captureTimeNs": "1763900000123456789", "frameIndex": "42", "status": "STATUS_INITIALISED",
        "theta": [0.5, -1.25, 0.96875, 0.0, 3.0e-5, -2.5],
        "joints": [{"name": "pelvis", "px": 0.5, "py": -1.25, "pz": 0.96875, "qw": 1.0},
                   {"name": "l_femur", "px": 0.5, "py": -1.125, "pz": 0.96875, "qw": 0.5, "qx": 0.5, "qy": 0.5, "qz": -0.5}],
        "costs": {"orientation": 1.5, "position": 25.25, "acceleration": 0.0625, "pcaProjection": 0.5, "pcaDeviation": 2.0},
        "iterations": 3, "solveTimeMs": 1.125, "qualityFlags": 9, "cameras": ["cam0", "cam3"], "imus": ["pelvis"],
        "latencyMs": 1.75}, None),
    "health": ("mocap.v1.Health", {
        "source": "host", "timeNs": "1763900001000000000",
        "streams": [{"stream": "camera/cam0", "active": True, "rateHz": 59.5, "received": "3600", "dropped": "3", "late": "2",
                     "malformed": "1", "latencyP50Ms": 0.75, "latencyP99Ms": 2.5},
                    {"stream": "imu/pelvis", "rateHz": 0.0, "received": "100", "lost": "4"}],
        "latencyP50Ms": 1.25, "latencyP99Ms": 3.5, "framesSolved": "3600", "framesDropped": "1"}, None),
    # The host's link to one input endpoint: a publisher there refused at the handshake (field 18).
    "health_link": ("mocap.v1.Health", {
        "source": "host", "timeNs": "1763900002000000000",
        "streams": [{"stream": "link/tcp://box-1.local:5600", "active": True, "handshakeFailures": "17"},
                    {"stream": "link/tcp://hub.local:5601", "handshakeFailures": "300"}],
        "framesSolved": "60"}, None),
    # A camera whose clock stepped away and back (a PTP loss), its frames refused meanwhile.
    "health_clock_steps": ("mocap.v1.Health", {
        "source": "host", "timeNs": "1763900002000000000",
        "streams": [{"stream": "camera/cam2", "active": True, "rateHz": 60.0, "received": "7200", "dropped": "61",
                     "latencyP50Ms": 6.5, "latencyP99Ms": 9.25, "clockSteps": "2"}],
        "framesSolved": "7200"}, None),
    # A session of several people: one PoseFrame per person, each with its subject id.
    "pose_frame_subject": ("mocap.v1.PoseFrame", {
        "captureTimeNs": "1763900000140123456", "frameIndex": "43", "theta": [1.5, 0.25, 0.9375],
        "joints": [{"name": "pelvis", "px": 1.5, "py": 0.25, "pz": 0.9375, "qw": 1.0}],
        "costs": {"position": 12.5}, "iterations": 2, "cameras": ["cam1", "cam2"], "subjectId": 3}, None),
    # ... and the host's Health says whom it tracks.
    "health_people": ("mocap.v1.Health", {
        "source": "host", "timeNs": "1763900003000000000",
        "streams": [{"stream": "camera/cam1", "active": True, "rateHz": 60.0, "received": "180"}],
        "framesSolved": "180",
        "people": {"tracked": 2, "born": "3", "retired": "1", "foundAgain": "2", "viewsDropped": "5",
                   "viewsUnexplained": "40", "suitsWorn": 2, "suitChanges": "2", "suitsDoubted": "1"}}, None),
    "calibration": ("mocap.v1.Calibration", {
        "source": "calibrator", "sequence": "2", "validFromNs": "1763900012000000000",
        "skeletonJson": '{"format": "mocap.skeleton/1", "bones": []}',
        "imusJson": '{"format": "mocap.imus/1", "imus": []}',
        "layoutJson": '{"format": "mocap.layout/1", "name": "coco17", "keypoints": []}',
        "reportJson": '{"window_start_s": 3.0, "note": "\u00e9t\u00e9"}'}, None),
}
ENCODERS = {"mocap.v1.ImuBatch": imu_batch, "mocap.v1.PoseFrame": pose_frame, "mocap.v1.Health": health,
            "mocap.v1.Calibration": calibration}
# Bytes no reader may accept: (type, bytes).
REJECTED = {
    "keypoint_frame_truncated": ("mocap.v1.KeypointFrame", keypoint_frame(KEYPOINT_FRAME)[:-7]),
    "imu_batch_bad_length": ("mocap.v1.ImuBatch", text(1, "hub0") + key(4, 2) + varint(1000) + b"\x0a\x01"),
}


def main() -> None:
    index = {}
    for name, (type_name, message, data) in VECTORS.items():
        data = data if data is not None else ENCODERS[type_name](message)
        (HERE / f"{name}.bin").write_bytes(data)
        (HERE / f"{name}.json").write_text(json.dumps(message, indent=2) + "\n")
        index[name] = {"type": type_name, "unknown_fields": name.endswith("unknown_fields")}
    for name, (type_name, data) in REJECTED.items():
        (HERE / f"{name}.bin").write_bytes(data)
        index[name] = {"type": type_name, "rejected": True}
    (HERE / "index.json").write_text(json.dumps(index, indent=2) + "\n")


if __name__ == "__main__":
    main()
