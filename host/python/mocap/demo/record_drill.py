"""Drills of the recorder: a real `mocap record` process fed a simulated studio's streams
(8 cameras at 60 fps, 13 IMUs at 100 Hz: what its edge boxes send) in real time from this
process on loopback, stopped (SIGTERM, as `systemctl stop`) or killed (SIGKILL) mid-take;
then what the file it left holds (`mocap bench --only recording`, tests/test_recording_drill.py).
"""

from __future__ import annotations

import dataclasses
import math
import signal as signals
import statistics
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import zmq
from mcap.reader import make_reader

from mocap.demo import studio as live_studio
from mocap.errors import InputError
from mocap.net import wire
from mocap.recording import reader, recorder, recover, replay
from mocap_edge import offline

TIMEOUT_S = 30.0  # bound on waits for the recorder process; generous for loaded machines
PREPARE_S = 0.3  # between the recorder's subscription and the take's start: the messages are made then


@dataclasses.dataclass
class Drill:
    path: Path  # the file the recorder left
    sent: list[tuple[int, bytes]]  # (send time ns, payload) of every message sent before the signal
    signal_ns: int  # when the signal was sent
    returncode: int


def studio_streams(folder: Path, seconds: float, seed: int = 1) -> tuple[Path, list[tuple[int, object]]]:
    """A simulated studio's session, and its edge boxes' messages as (arrival ns, message)
    in the order they reach the host (mocap_edge.offline), for a take that starts at 0."""
    studio = live_studio.prepare(folder, seconds=seconds, seed=seed, calibration="oracle")
    return studio.session, offline.studio_messages(studio.streams, 0, studio.detect_every)


def _now(messages: list[tuple[int, object]], seconds: float, start_ns: int) -> list[tuple[int, list[bytes]]]:
    """The first `seconds` of the messages encoded with their times moved to a take that
    starts at start_ns (a live host would drop a take from long ago)."""
    out = []
    for offset_ns, message in messages:
        if offset_ns > seconds * 1e9:
            break
        moved = type(message)()
        moved.CopyFrom(message)
        replay.shift(moved, start_ns)
        out.append((offset_ns, wire.encode(moved)))
    return out


def run(folder: Path, session: Path, messages: list[tuple[int, object]], sig: int, after_s: float,
        settle: bool = False) -> Drill:
    """Starts `mocap record --session session` into folder/take.mcap, sends it `messages`
    at their pace once it has subscribed, sends `sig` after_s into them (settle: only once
    the file holds every message sent, so that the signal finds nothing in flight), and
    waits for the recorder to end."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "take.mcap"
    with zmq.Context() as context, context.socket(zmq.XPUB) as publisher:
        publisher.setsockopt(zmq.LINGER, 0)
        port = publisher.bind_to_random_port("tcp://127.0.0.1")
        process = subprocess.Popen([sys.executable, "-m", "mocap.cli", "record", "--connect", f"tcp://127.0.0.1:{port}",
                                    "--session", str(session), "--out", str(path)], stdout=subprocess.DEVNULL)
        try:
            if not publisher.poll(TIMEOUT_S * 1000):
                raise InputError(f"the recorder did not subscribe within {TIMEOUT_S:.0f} s")
            publisher.recv()  # its subscription
            start_ns = time.time_ns() + int(PREPARE_S * 1e9)
            sent = _send(publisher, _now(messages, after_s, start_ns), after_s, start_ns)
            if settle:
                _wait_for(path, {payload for _, payload in sent})
            signal_ns = time.time_ns()
            process.send_signal(sig)
            returncode = process.wait(timeout=TIMEOUT_S)
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()
    return Drill(path, sent, signal_ns, returncode)


def _send(publisher: zmq.Socket, messages: list[tuple[int, list[bytes]]], seconds: float,
          start_ns: int) -> list[tuple[int, bytes]]:
    """Sends the messages at their pace from start_ns on, and returns when `seconds` have
    passed since; (send time ns, payload) of each."""
    start = time.monotonic() + (start_ns - time.time_ns()) * 1e-9
    sent = []
    for offset_ns, frames in messages:
        time.sleep(max(0.0, start + offset_ns * 1e-9 - time.monotonic()))
        publisher.send_multipart(frames)
        sent.append((time.time_ns(), frames[1]))
    time.sleep(max(0.0, start + seconds - time.monotonic()))
    return sent


def _wait_for(path: Path, payloads: set[bytes]) -> None:
    """Until the recording being written holds every payload (its chunks reach the file
    every recorder.CHUNK_S); InputError after TIMEOUT_S."""
    deadline = time.monotonic() + TIMEOUT_S
    while time.monotonic() < deadline:
        with reader.Recording(path, warn=False) as recording:
            if payloads <= {m.payload for m in recording.messages()}:
                return
        time.sleep(recorder.CHUNK_S)
    raise InputError(f"{path}: the recorder did not write what it was sent within {TIMEOUT_S:.0f} s")


def lost(drill: Drill, path: Path | None = None) -> dict:
    """What of the messages sent before the signal `path` (default: the file left) lacks:
    how many, and how long before the signal the oldest of them was sent (s; 0 if none)."""
    with reader.Recording(path or drill.path, warn=False) as recording:
        kept = {m.payload for m in recording.messages()}
        integrity = recording.integrity
    missing = [t for t, payload in drill.sent if payload not in kept]
    return {"messages_lost": len(missing), "lost_s": (drill.signal_ns - min(missing)) * 1e-9 if missing else 0.0,
            "intact": integrity.intact, "complete": integrity.complete}


def indexed_count(path: Path) -> int:
    """Messages an independent reader finds through the file's index (the `mcap` library's
    indexed reader: it reads the summary, then the chunks it lists)."""
    with open(path, "rb") as stream:
        mcap_reader = make_reader(stream)
        if mcap_reader.get_summary() is None:
            raise InputError(f"{path}: no summary")
        return sum(1 for _ in mcap_reader.iter_messages())


def size_overhead(session: Path, messages: list[tuple[int, object]], folder: Path) -> dict:
    """File size with chunks closed every chunk_s (the recorder's clock following the
    messages' arrival) against chunks closed at recorder.CHUNK_BYTES only, in percent."""
    sizes = {}
    for chunk_s in (0.1, 0.25, 0.5, 1.0, math.inf):
        clock = [0.0]
        path = folder / f"chunks_{chunk_s}.mcap"
        with recorder.Recorder(path, chunk_s=chunk_s, clock=lambda: clock[0]) as r:
            r.attach_session(session)
            for offset_ns, message in messages:
                clock[0] = offset_ns * 1e-9
                r.write(wire.encode(message), offset_ns)
        sizes[chunk_s] = path.stat().st_size
    return {str(k): round(100.0 * (v / sizes[math.inf] - 1.0), 2) for k, v in sizes.items() if k != math.inf}


def memory_growth(messages: list[tuple[int, object]], folder: Path, minutes: float = 4.0) -> float:
    """MB the recorder's Python heap grows per 10 minutes of the studio's messages (the take
    repeated, its times moved on; the recorder's clock following them), after a 2-minute
    warm-up, by tracemalloc: the chunk index it keeps until the file is closed."""
    encoded = [(t, wire.encode(m)) for t, m in messages]
    span_ns, clock, marks = messages[-1][0] + 1, [0.0], []
    tracemalloc.start()
    try:
        with recorder.Recorder(folder / "long.mcap", clock=lambda: clock[0]) as r:
            for loop in range(math.ceil(minutes * 60e9 / span_ns)):
                for offset_ns, frames in encoded:
                    clock[0] = (loop * span_ns + offset_ns) * 1e-9
                    r.write(frames, loop * span_ns + offset_ns)
                marks.append((clock[0], tracemalloc.get_traced_memory()[0]))
    finally:
        tracemalloc.stop()
    after = [(t, b) for t, b in marks if t >= 120.0]
    return (after[-1][1] - after[0][1]) / 1e6 / (after[-1][0] - after[0][0]) * 600.0


def bench(kills: int = 5, seconds: float = 6.0) -> dict:
    """The `recording` benchmark line: the studio's data rate, what the chunk period costs in
    file size, what SIGKILL loses (`kills` drills, killed 2.0-4.5 s into the take) and
    SIGTERM leaves, and how the recorder's heap grows over a long take."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        session, messages = studio_streams(folder / "studio", seconds)
        rate = sum(m.ByteSize() for _, m in messages) / (messages[-1][0] * 1e-9)
        losses, counts = [], []
        for k in range(kills):
            drill = run(folder / f"kill{k}", session, messages, signals.SIGKILL, 2.0 + 2.5 * k / max(1, kills - 1))
            recover.recover(drill.path, folder / f"kill{k}" / "recovered.mcap")
            losses.append(lost(drill, folder / f"kill{k}" / "recovered.mcap"))
            counts.append(indexed_count(folder / f"kill{k}" / "recovered.mcap"))
        term = run(folder / "term", session, messages, signals.SIGTERM, 3.0)
        return {"bench": "recording", "chunk_s": recorder.CHUNK_S, "studio_bytes_per_s": round(rate),
                "size_overhead_pct_by_chunk_s": size_overhead(session, messages, folder),
                "sigkill_lost_s_max": round(max(x["lost_s"] for x in losses), 3),
                "sigkill_lost_s_median": round(statistics.median(x["lost_s"] for x in losses), 3),
                "sigkill_messages_lost": [x["messages_lost"] for x in losses], "recovered_indexed_messages": counts,
                "sigterm_intact": lost(term)["intact"], "sigterm_messages_lost": lost(term)["messages_lost"],
                "recorder_heap_growth_mb_per_10min": round(memory_growth(messages, folder), 3)}
