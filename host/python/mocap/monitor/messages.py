"""mocapd's PoseFrame and Health as the page's JSON messages ("pose", "health"); "scene" is in
scene.py. Positions in metres, world frame, rounded to 0.1 mm; times in seconds on the shared
timebase (a JSON number holds nanoseconds since 1970 only to ~0.2 µs)."""

from __future__ import annotations

from typing import Any

from mocap.net import wire

STREAM_FIELDS = ("rate_hz", "received", "lost", "late", "dropped", "malformed", "latency_p50_ms", "latency_p99_ms",
                 "heading_correction_deg", "clock_residual_us", "handshake_failures")
STATUS = {v.number: v.name.removeprefix("STATUS_").lower() for v in wire.PoseFrame.Status.DESCRIPTOR.values}


def pose(frame: wire.PoseFrame) -> dict[str, Any]:
    """The solved pose of one performer (`subject`: 0 in a session of one, else the host's id of
    the person): each joint's centre (the skeleton's bone order, named), its status and costs,
    the inputs it used."""
    return {
        "type": "pose", "subject": frame.subject_id, "frame": frame.frame_index, "time_s": frame.capture_time_ns * 1e-9,
        "status": STATUS.get(frame.status, str(frame.status)), "latency_ms": round(frame.latency_ms, 3),
        "solve_ms": round(frame.solve_time_ms, 3), "iterations": frame.iterations,
        "names": [j.name for j in frame.joints],
        "joints": [[round(j.px, 4), round(j.py, 4), round(j.pz, 4)] for j in frame.joints],
        "cameras": list(frame.cameras), "imus": list(frame.imus), "distrusted": list(frame.imus_distrusted),
    }


def stream_state(stream: wire.Health) -> str:
    """"ok", "stale" (nothing from it lately: the host's own judgement, `active`) or "distrusted"
    (an IMU the solve leaves out: its orientation contradicts the keypoints)."""
    if stream.distrusted:
        return "distrusted"
    return "ok" if stream.active else "stale"


def health(message: wire.Health) -> dict[str, Any]:
    """The host's Health: every stream with its state and counters, the host's latency and, in a
    session of several people, its people counters (else None)."""
    streams = [{"name": s.stream, "state": stream_state(s), **{k: _round(getattr(s, k)) for k in STREAM_FIELDS}}
               for s in message.streams]
    people = ({f.name: getattr(message.people, f.name) for f in message.people.DESCRIPTOR.fields}
              if message.HasField("people") else None)
    return {"type": "health", "source": message.source, "time_s": message.time_ns * 1e-9, "streams": streams,
            "latency_p50_ms": _round(message.latency_p50_ms), "latency_p99_ms": _round(message.latency_p99_ms),
            "frames_solved": message.frames_solved, "frames_dropped": message.frames_dropped, "people": people}


def _round(value: float | int) -> float | int:
    return round(value, 3) if isinstance(value, float) else value
