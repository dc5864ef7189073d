"""What a drill's recording holds against what the edge boxes published, counted by their
sequence numbers (mocap.demo.drill): a camera box publishes every frame of its source in
order (KeypointFrame.frame_index, the stream file's frame number), the IMU hub every batch in
order (ImuBatch.sequence, from 0 in each run of the process). Within a run of a publisher a
missing number is a message the recorder lost; a killed box's own frames are those its
simulated detector had finished (sim: model, the box's seed) before the kill."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np

from mocap.demo.studio import Studio
from mocap.net import wire
from mocap.recording import reader
from mocap_edge.detect.sim import SimulatedDetector

IN_FLIGHT_NS = 20_000_000  # a frame ready this shortly before the kill may not have left the box


def _read(path: Path) -> tuple[dict[str, list[tuple[int, int]]], list[tuple[int, int]]]:
    """(log time, frame index) per camera, (log time, sequence) of the hub's batches."""
    cameras, batches = defaultdict(list), []
    with reader.Recording(path, warn=False) as recording:
        for m in recording.messages():
            if m.type_name not in ("mocap.v1.KeypointFrame", "mocap.v1.ImuBatch"):
                continue
            message = wire.decode([m.type_name.encode(), m.payload])
            if isinstance(message, wire.KeypointFrame):
                cameras[message.camera_id].append((m.log_time_ns, message.frame_index))
            else:
                batches.append((m.log_time_ns, message.sequence))
    return cameras, batches


def _missing(numbers: list[int]) -> int:
    """Numbers absent between the least and the greatest of a run."""
    return int(max(numbers) - min(numbers) + 1 - len(set(numbers))) if numbers else 0


def _killed_camera(s: Studio, start_ns: int, camera: str, frames: list[tuple[int, int]], kill: dict) -> dict:
    """The killed box: its frames finished before the kill that the file lacks (lost, and
    in flight at the kill), the frames of its run after the restart that it lacks, and the
    gap in the file (s of take time)."""
    c = s.camera_ids.index(camera)
    ready = SimulatedDetector(str(s.streams), camera, start_ns=start_ns, seed=c).ready_ns
    before = [f for t, f in frames if t < kill["killed_ns"]]
    after = [f for t, f in frames if t >= kill["restarted_ns"]]
    finished = np.flatnonzero(ready < kill["killed_ns"])
    finished = finished[finished >= min(before)]
    absent = np.setdiff1d(finished, before)
    in_flight = int((ready[absent] >= kill["killed_ns"] - IN_FLIGHT_NS).sum())
    times = s.frame_times
    return {"lost": len(absent) - in_flight + _missing(after), "in_flight_at_kill": in_flight,
            "gap_s": float(times[min(after)] - times[max(before)]) if after else None,
            "run_after_restart_from_s": (float(times[min(after)]) if after else None)}


def check(path: Path, s: Studio, start_ns: int, killed: dict[str, dict]) -> dict:
    """The recording at path of a take of studio s that started at start_ns; killed: the
    publishers killed and restarted ({camera id or "hub0": {"killed_ns", "restarted_ns"}})."""
    cameras, batches = _read(path)
    out = {"messages": sum(map(len, cameras.values())) + len(batches), "lost": {}}
    for camera in s.camera_ids:
        frames = cameras.get(camera, [])
        if camera in killed:
            out[camera] = _killed_camera(s, start_ns, camera, frames, killed[camera])
            out["lost"][camera] = out[camera]["lost"]
        else:
            out["lost"][camera] = _missing([f for _, f in frames])
    runs, run = [], []
    for t, sequence in batches:  # a new run where the sequence starts again
        if run and sequence <= run[-1]:
            runs.append(run)
            run = []
        run.append(sequence)
    runs.append(run)
    out["lost"]["hub0"] = sum(_missing(r) for r in runs)
    out["hub0_runs"] = len([r for r in runs if r])
    if "hub0" in killed:
        times = [t for t, _ in batches]
        before = max((t for t in times if t < killed["hub0"]["killed_ns"]), default=None)
        after = min((t for t in times if t >= killed["hub0"]["restarted_ns"]), default=None)
        out["hub0_gap_s"] = (after - before) * 1e-9 if before and after else None
    return out
