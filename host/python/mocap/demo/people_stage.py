"""Several performers live (`mocap bench --only multi`, the `live` part): a simulated scene of
three performers in suits (mocap.sim.people: every camera's frames with every person it found,
each suit's batches) recorded, then published by `mocap replay --restamp` into mocapd (a
session of three people and their three suits) as a take happening now, as the stage
benchmark does. Reported: the host's latency over every PoseFrame (three per frame), the
frames it solved, and the scene scored as `mocap eval --people` scores it."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from mocap.demo import stage
from mocap.demo.studio import free_ports
from mocap.eval import people
from mocap.recording import recorder
from mocap.sim import messages as sim_messages
from mocap.sim import people as sim_people


def record(scene: sim_people.Scene, path: Path) -> Path:
    """The scene's messages as a recording, logged at their arrival."""
    with recorder.Recorder(path) as r:
        for arrival_ns, type_name, payload in sim_messages.scene_messages(scene, suits=True):
            r.write([type_name.encode(), payload], arrival_ns)
    return path


def _offset_ns(scene: sim_people.Scene, poses: list) -> int:
    """The replay's restamping: of the first frames' times, the shift that matches most poses."""
    frame_ns = sim_messages.frame_times_ns(scene.performers[0])
    captured = {p.capture_time_ns for p in poses}
    first = min(captured)
    return max((first - f for f in frame_ns[:10]), key=lambda off: sum(f + off in captured for f in frame_ns))


def live(scene: sim_people.Scene, folder: Path, realtime: bool = True) -> dict:
    """The scene through mocapd, scored."""
    output = f"tcp://127.0.0.1:{free_ports(1)[0]}"
    session = people.write_session(scene, folder, True, ["tcp://127.0.0.1:1"], output)
    duration = float(scene.performers[0].times[-1]) + stage.START_S
    poses, healths, summary = stage.replayed(session, output, record(scene, folder / "take.mcap"), duration, realtime)
    frames = people.by_frame(scene, poses, _offset_ns(scene, poses))
    scored = people.score(scene, frames)
    latency = np.array([p.latency_ms for p in poses])
    solved = sum(1 for f in frames if f)
    return {"frames": len(frames), "frames_published": solved, "pose_frames": len(poses),
            "latency_p50_ms": round(float(np.median(latency)), 2),
            "latency_p99_ms": round(float(np.percentile(latency, 99)), 2),
            "latency_max_ms": round(float(latency.max()), 2),
            "identity_swaps": sum(r["identity_swaps"] for r in scored),
            "suits_found_s": [r["own_suit_from_s"] for r in scored],
            "joint_centres_pos_cm": [r["joint_centres_pos_cm"] for r in scored],
            "people": dict(zip(("tracked", "born", "suits_worn"),
                               (healths[-1].people.tracked, healths[-1].people.born, healths[-1].people.suits_worn)))
            if healths else None,
            "host_dropped_inputs": summary.get("dropped"), "host_realtime": summary.get("realtime")}


def bench(seconds: float = 8.0, seed: int = 0, realtime: bool = True) -> dict:
    """The live part of the multi benchmark line."""
    from mocap import paths
    from mocap.sim.take import Config

    clips = [paths.shared_file(f"data/mocap/{c}") for c in people.BENCH_CLIPS]
    scene = sim_people.simulate(clips, 3, seconds, Config(preset="hq13"), np.random.default_rng(seed))
    with tempfile.TemporaryDirectory() as folder:
        return live(scene, Path(folder), realtime)
