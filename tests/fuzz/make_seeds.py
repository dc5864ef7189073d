"""Writes the fuzz targets' seed corpora, tests/fuzz/corpus/<target>/seed_*, from the golden
vectors (tests/golden/: the wire messages and proto/can's frames), the shipped data files and
the fixture take (tests/fuzz/take/). Deterministic: run it again after a format changes.
Inputs a target once failed on are kept beside the seeds as regression_* (never rewritten).

    .venv/bin/python tests/fuzz/make_seeds.py [--take]   (--take: write the fixture take first)
"""

from __future__ import annotations

import json
import shutil
import struct
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FUZZ = ROOT / "tests/fuzz"
CORPUS = FUZZ / "corpus"
GOLDEN = ROOT / "tests/golden"
DATA = ROOT / "host/data"
SESSION = ROOT / "host/fuzz/data"
WIRE_TYPES = ["mocap.v1.KeypointFrame", "mocap.v1.ImuBatch", "mocap.v1.PoseFrame", "mocap.v1.Health",
              "mocap.v1.Calibration"]  # host/fuzz/fuzz_wire.cc's selectors 0..4


def _write(target: str, seeds: dict[str, bytes]) -> None:
    folder = CORPUS / target
    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.glob("seed_*"):
        old.unlink()
    for name, data in seeds.items():
        (folder / f"seed_{name}").write_bytes(data)


def _record(type_name: str, payload: bytes, ms: int = 17) -> bytes:
    return bytes([WIRE_TYPES.index(type_name)]) + struct.pack("<H", len(payload)) + payload + bytes([ms])


def _can_frames() -> list[tuple[str, int, bytes]]:
    """(message, identifier, data) of proto/can's golden vectors."""
    out = []
    for line in (GOLDEN / "can_frames.txt").read_text().splitlines():
        if line and not line.startswith("#"):
            name, _, ident, data = line.split()[:4]
            out.append((name, int(ident, 16), bytes.fromhex(data)))
    return out


def wire_seeds() -> dict[str, bytes]:
    from mocap.v1 import imu_batch_pb2, keypoint_frame_pb2

    index = json.loads((GOLDEN / "index.json").read_text())
    seeds = {name: _record(e["type"], (GOLDEN / f"{name}.bin").read_bytes()) for name, e in index.items()}
    # A studio of the fixture session: both cameras' frames of one person (coco17), then the IMUs.
    imus = [s["name"] for s in json.loads((DATA / "imus13.json").read_text())["imus"]]
    studio = b""
    for k in range(3):
        for cam in ("cam0", "cam1"):
            f = keypoint_frame_pb2.KeypointFrame(camera_id=cam, frame_index=k, keypoint_layout="coco17",
                                                 capture_time_ns=1_763_900_000_000_000_000 + k * 16_666_667,
                                                 detected=True)
            for person in range(2):
                f.persons.add(x=[600.0 + 5 * i + 300 * person for i in range(17)], y=[300.0 + 8 * i for i in range(17)],
                              confidence=[0.9] * 17)
            studio += _record("mocap.v1.KeypointFrame", f.SerializeToString(), 0)
        b = imu_batch_pb2.ImuBatch(hub_id="hub0", sequence=k, send_time_ns=1_763_900_000_000_000_000 + k * 10_000_000)
        for i, name in enumerate(imus):
            b.samples.add(sensor_id=name, sample_time_ns=1_763_900_000_000_000_000 + k * 10_000_000, qw=1.0,
                          az=9.81, packet_counter=k)
        studio += _record("mocap.v1.ImuBatch", b.SerializeToString(), 16)
    seeds["studio"] = studio
    return seeds


def session_seeds() -> dict[str, bytes]:
    files = ["session.json", "skeleton_default.json", "rig.json", "layouts/coco17.json", "imus13.json",
             "prior_default.json"]  # host/fuzz/fuzz_session.cc's selectors 0..5
    return {Path(f).stem: bytes([i]) + ((SESSION if i in (0, 2) else DATA) / f).read_bytes()
            for i, f in enumerate(files)}


def calibration_seeds() -> dict[str, bytes]:
    from mocap.v1 import calibration_pb2

    def pieces(skeleton: bytes, layout: bytes, imus: bytes, source: bytes) -> bytes:
        return b"".join(struct.pack("<H", len(p)) + p for p in (skeleton, layout, imus)) + source

    golden = calibration_pb2.Calibration.FromString((GOLDEN / "calibration.bin").read_bytes())
    shipped = [(DATA / f).read_bytes() for f in ("skeleton_default.json", "layouts/coco17.json", "imus13.json")]
    return {"shipped": pieces(*shipped, b"calibrator"),
            "golden": pieces(golden.skeleton_json.encode(), golden.layout_json.encode(), golden.imus_json.encode(),
                             golden.source.encode())}


def can_protocol_seeds() -> dict[str, bytes]:
    frames = _can_frames()
    records = [bytes([5]) + struct.pack("<H", ident) + bytes([len(data)]) + data.ljust(8, b"\0")
               for _, ident, data in frames]
    return {"golden": b"".join(records), **{f"frame{i}": r for i, r in enumerate(records)}}


def node_seeds() -> dict[str, bytes]:
    to_node = [(ident, data) for name, ident, data in _can_frames() if name in ("Sync", "Command")]
    poll = bytes([2]) + struct.pack("<H", 20)
    frames = [bytes([0]) + struct.pack("<H", ident) + bytes([len(data)]) + data.ljust(8, b"\0") + poll
              for ident, data in to_node]
    return {"golden": b"".join(frames), "heartbeats": poll * 4 + bytes([2]) + struct.pack("<H", 1500)}


def slcan_seeds() -> dict[str, bytes]:
    lines = [f"t{ident:03X}{len(data)}{data.hex().upper()}\r" for _, ident, data in _can_frames()]
    return {"open_frames": ("\r\rV\rN\rS8\rO\r" + "".join(lines) + "F\rC\r").encode(),
            "refused": b"T12345678100\rr1230\rt12\rX\rO\rt7FF9\r" + b"t" * 40 + b"\r"}


def hub_frames_seeds() -> dict[str, bytes]:
    def frame(ident: int, data: bytes, ms: int = 1) -> bytes:
        return bytes([0]) + struct.pack("<H", ident) + bytes([0, len(data)]) + data.ljust(8, b"\0") + struct.pack("<H", ms)

    frames = _can_frames()
    sync = [bytes([3, 201]) + struct.pack("<H", 2)]
    return {"golden": b"".join(sync + [frame(i, d) for _, i, d in frames]),
            **{f"{name}{k}": frame(i, d) for k, (name, i, d) in enumerate(frames)}}


def hub_config_seeds() -> dict[str, bytes]:
    from mocap_edge.hub.config import HubConfig

    config = HubConfig({1: "pelvis", 2: "head"}, {0x68: "hand_l"}, rate_hz=100, mode="9d")
    return {"config": config.to_toml().encode(), "minimal": b'[nodes]\n1 = "pelvis"\n'}


def take_seeds() -> dict[str, bytes]:
    files = sorted(p.relative_to(FUZZ / "take") for p in (FUZZ / "take").rglob("*") if p.is_file())
    return {str(f).replace("/", "_"): bytes([i]) + (FUZZ / "take" / f).read_bytes() for i, f in enumerate(files)}


def bvh_seeds() -> dict[str, bytes]:
    import importlib.util
    import tempfile

    import numpy as np

    from mocap import _core, paths
    from mocap.io import bvh_export

    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    thetas = np.zeros((3, skeleton.pose_dim))
    thetas[:, 2] = 0.95
    thetas[1, 3:] = 0.1
    spec = importlib.util.spec_from_file_location("clip", ROOT / "host/python/tests/test_bvh_retarget.py")
    clip = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(clip)  # its MotionBuilder-style CLIP, two frames of zeros
    zeros = "\n".join(" ".join(["0"] * clip.WIDTH) for _ in range(2))
    with tempfile.TemporaryDirectory() as d:
        bvh_export.write_bvh(Path(d) / "clip.bvh", skeleton, thetas, 60.0)
        return {"exported": (Path(d) / "clip.bvh").read_bytes(), "motionbuilder": (clip.CLIP + zeros + "\n").encode()}


def vmc_seeds() -> dict[str, bytes]:
    zero = [0.0] * 67
    zero[2] = 0.95
    bent = [0.2 * ((i * 7) % 5 - 2) for i in range(67)]
    bent[66] = 12.5
    return {"zero": struct.pack("<67d", *zero), "bent": struct.pack("<67d", *bent)}


def write_take() -> None:
    """The fixture take: 2 cameras, 3 frames (coco17), 2 IMUs at 100 Hz, of the simulated studio."""
    import numpy as np

    from mocap import _core
    from mocap.io import take_folder
    from mocap.sim import take_out

    take, _ = take_out.simulate(0.5, "hq6", seed=1, layout="coco17")
    take.n_frames, take.rig = 3, _core.Rig(list(take.rig.cameras)[:2])
    take.people = [[np.round(p, 1) for p in cam[:3]] for cam in take.people[:2]]
    for m in take.imus[:2]:
        m.times_s, m.quaternions, m.accelerations = m.times_s[:6], m.quaternions[:6], m.accelerations[:6]
    take.imus = take.imus[:2]
    shutil.rmtree(FUZZ / "take", ignore_errors=True)
    take_folder.write_take(FUZZ / "take", take)


def main() -> None:
    if "--take" in sys.argv:
        write_take()
    for target, make in [("fuzz_wire", wire_seeds), ("fuzz_session", session_seeds),
                         ("fuzz_calibration", calibration_seeds), ("fuzz_can_protocol", can_protocol_seeds),
                         ("fuzz_node_commands", node_seeds), ("fuzz_slcan", slcan_seeds),
                         ("fuzz_hub_frames", hub_frames_seeds), ("fuzz_hub_config", hub_config_seeds),
                         ("fuzz_take", take_seeds), ("fuzz_bvh", bvh_seeds), ("fuzz_vmc", vmc_seeds)]:
        _write(target, make())


if __name__ == "__main__":
    main()
