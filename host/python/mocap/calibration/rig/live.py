"""Board-free calibration live, from the camera boxes' streams: what they send is recorded as
it comes (a recording, so nothing received is lost and the estimate can be made again later),
and every `every_s` the rig is estimated from everything received so far and written over the
same Calib.toml, each estimate compared with the one before (how far the cameras moved), so
the crew sees it settle while the person walks about. Ends after `seconds` or when stopped,
with a last estimate from the whole recording."""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable
from pathlib import Path

from mocap import _core
from mocap.calibration.rig import calibrate, compare, recorded
from mocap.errors import InputError
from mocap.io import calib_toml
from mocap.recording import recorder

Intrinsics = Callable[[recorded.Detections], list]


def estimate(recording: Path, intrinsics: Intrinsics, height_m: float) -> tuple[_core.Rig, dict]:
    """The rig from what `recording` holds so far, and its report."""
    detections = recorded.read(recording)
    cameras = intrinsics(detections)
    return calibrate.calibrate(cameras, detections.people, detections.layout, detections.rate, height_m)


def write(rig: _core.Rig, out: Path) -> None:
    """Replaces `out` at once: a reader never sees half a file."""
    partial = out.with_name(out.name + ".partial")
    partial.write_text(calib_toml.dumps(rig))
    os.replace(partial, out)


def run(endpoints: list[str], recording: Path, out: Path, height_m: float, intrinsics: Intrinsics,
        seconds: float, every_s: float, report: Callable[[dict], None], session: Path | None = None,
        stop: threading.Event | None = None) -> dict:
    """Records the streams into `recording` for `seconds` (or until stop), estimating the rig
    every `every_s` from what came so far and once more at the end; report receives a line per
    estimate (or why there is none yet). The last line."""
    if not every_s > 0 or not seconds > 0:
        raise InputError("--seconds and --every must be above 0")
    recorder.check_endpoints(endpoints)
    stop = stop or threading.Event()
    worker = threading.Thread(target=recorder.record, args=(endpoints, recording, seconds, stop),
                              kwargs={"session": session}, name="calibrate-rig-record", daemon=True)
    start = time.monotonic()
    worker.start()
    previous, line = None, {}
    while True:
        worker.join(timeout=every_s)
        done = not worker.is_alive()
        line = {"after_s": round(time.monotonic() - start, 1), "final": done}
        try:
            rig, found = estimate(recording, intrinsics, height_m)
        except InputError as e:
            report({**line, "waiting": str(e)})
            if done:
                raise
            continue
        write(rig, out)
        line.update({"out": str(out), "frames": found["frames"], "up_from": found["up_from"],
                     "reprojection_px_median": round(found["reprojection_px_median"], 3)})
        if previous is not None and [c.name for c in previous.cameras] == [c.name for c in rig.cameras]:
            moved = compare.compare(rig, previous)
            line.update({"moved_cm_max": round(moved["position_cm_max"], 3),
                         "turned_deg_max": round(moved["orientation_deg_max"], 3)})
        report(line)
        previous = rig
        if done:
            return line
