"""The live host before a stage of dozens of cameras (`mocap bench --only stage`): the simulated
studio's messages (every camera box's KeypointFrame and the IMU hub's ImuBatch, as
mocap_edge.offline makes them) recorded, then published by `mocap replay --restamp` into mocapd as
a take happening now. Such a stage's edge is dozens of boxes, each a machine of its own; played
by dozens of simulated box processes on this 2-core machine (`mocap bench --only live
--live-cameras 32`) the edge takes the cores the host is measured on, one replay process leaves
them to the host."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import zmq

from mocap.demo import play
from mocap.demo.score import score
from mocap.demo.studio import Studio, free_ports, prepare
from mocap.errors import InputError
from mocap.io.session import Session
from mocap.net import transport, wire
from mocap.recording import recorder
from mocap_edge import offline

START_S = 8.0  # mocapd's run beyond the take: the replay's start (an interpreter, the first subscriber)


def record(studio: Studio, path: Path) -> Path:
    """The studio's edge messages as a recording, logged at their arrival (the take from 0)."""
    with recorder.Recorder(path) as r:
        for arrival_ns, message in offline.studio_messages(studio.streams, 0, studio.detect_every):
            r.write(wire.encode(message), arrival_ns)
    return path


def _offset_ns(studio: Studio, poses: list) -> int:
    """The replay's restamping (capture times moved to its start): of the first frames' times,
    the one that matches most of the poses' capture times."""
    frame_ns = np.round(studio.frame_times * 1e9).astype(np.int64)
    captured = {p.capture_time_ns for p in poses}
    first = min(captured)
    return max((first - int(f) for f in frame_ns[:10]), key=lambda off: sum(int(f) + off in captured for f in frame_ns))


def replayed(session: Path, output: str, recording: Path, duration_s: float, realtime: bool) -> tuple[list, list, dict]:
    """mocapd on `session` with one input, `mocap replay --restamp` of `recording` (bound on a
    free port, the session's inputs replaced by it), for duration_s: the poses and Health it
    published on `output` and its summary."""
    endpoint = f"tcp://127.0.0.1:{free_ports(1)[0]}"
    path = dataclasses.replace(Session.load(session), inputs=[endpoint]).save(session.parent / "session_replayed.json")
    host = subprocess.Popen(play.mocapd_command(path, duration_s, realtime), stdout=subprocess.PIPE, text=True)
    sub = transport.subscriber(zmq.Context.instance(), [output], keys=None)
    replayer = subprocess.Popen([sys.executable, "-m", "mocap.cli", "replay", str(recording), "--bind", endpoint,
                                 "--restamp"], stdout=subprocess.DEVNULL)
    poses, healths, summary = play.published(host, sub, [replayer])
    if not poses:
        raise InputError("mocapd published no pose (its log is above)")
    return poses, healths, summary


def _run(studio: Studio, recording: Path, realtime: bool) -> play.Run:
    """mocapd on the studio's session fed by the replay, and the poses it published."""
    duration = float(studio.frame_times[-1]) + START_S
    poses, healths, summary = replayed(studio.session, studio.endpoints["host"], recording, duration, realtime)
    return play.Run(poses, healths, summary, _offset_ns(studio, poses))


def bench(seconds: float = 60.0, cameras: int = 32, realtime: bool = True) -> dict:
    """The `stage` benchmark line: the host's latency and frames never solved with `cameras`
    cameras (33 keypoints, 60 fps) and 13 IMUs, the truth's calibration."""
    with tempfile.TemporaryDirectory() as folder:
        studio = prepare(Path(folder) / "studio", seconds, cameras=cameras, calibration="oracle")
        run = _run(studio, record(studio, Path(folder) / "take.mcap"), realtime)
        result = score(studio, run)
    return {"bench": "stage", "seconds": seconds, "cameras": cameras, "imus": 13,
            **{k: v for k, v in result.items() if k.endswith("_ms")}, "frames": result["frames"],
            "dropped": result["dropped"], "joint_centres_pos_cm": result.get("joint_centres_pos_cm"),
            "host_dropped_inputs": result["host_dropped"], "host_realtime": run.host_summary.get("realtime")}
