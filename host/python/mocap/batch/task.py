"""One take of a batch, as a Dask worker runs it: calibrated from its own first seconds,
solved, exported and reported into OUT/<name>/, with OUT/<name>/batch.json last (its content
hash, what was written, the take's figures). A take whose batch.json holds the same hash and
succeeded is not solved again. A failure is this take's result, never the batch's end."""

from __future__ import annotations

import dataclasses
import json
import time
import traceback
from pathlib import Path

from mocap.batch import videos
from mocap.batch.inputs import RECORDING, VIDEOS, Input, content_hash
from mocap.calibration import from_recording
from mocap.errors import InputError, MocapError
from mocap.eval import take_truth
from mocap.recording import offline, reader
from mocap.takes import solve as take_solve
from mocap.takes.export import SUFFIXES, export

RESULT = "batch.json"


@dataclasses.dataclass(frozen=True)
class Options:
    exports: tuple[str, ...] = ()  # formats of mocap.takes.export, beside take.bvh and joints.csv
    settings: tuple[str, ...] = ()  # take folders: solver options of the solve after the calibration

    def as_dict(self) -> dict:
        return {"exports": sorted(self.exports), "settings": list(self.settings)}


def run(take: Input, out_root: Path, options: Options) -> dict:
    """Solves one take into out_root/<take.name>; its result (what batch.json holds)."""
    started = time.monotonic()
    out = Path(out_root) / take.name
    digest = content_hash(take, options.as_dict())
    earlier = _earlier(out, digest)
    if earlier is not None:
        return {**earlier, "take": str(take.path), "skipped": True}
    result = {"name": take.name, "take": str(take.path), "kind": take.kind, "hash": digest}
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / RESULT).unlink(missing_ok=True)  # an earlier result of other inputs no longer holds
        figures = _solve(take, out, options)
        result.update(status="ok", **figures, exports=_exports(out, options.exports))
    except MocapError as e:
        result.update(status="failed", error=str(e))
    except Exception as e:  # a defect: this take's, with where it happened; the others go on
        result.update(status="failed", error=f"{type(e).__name__}: {e}", traceback=traceback.format_exc())
    result["seconds"] = round(time.monotonic() - started, 3)
    try:
        (out / RESULT).write_text(json.dumps(result, indent=1))
    except OSError as e:
        result.update(status="failed", error=f"{out / RESULT}: cannot write it: {e}")
    return {**result, "skipped": False}


def _earlier(out: Path, digest: str) -> dict | None:
    """The result of an earlier batch that solved the same inputs with the same options and code."""
    try:
        earlier = json.loads((out / RESULT).read_text())
    except (OSError, ValueError):
        return None
    ok = isinstance(earlier, dict) and earlier.get("hash") == digest and earlier.get("status") == "ok"
    return earlier if ok else None


def _solve(take: Input, out: Path, options: Options) -> dict:
    if take.kind == RECORDING:
        return _solve_recording(take.path, out)
    if take.kind == VIDEOS:  # detected into out/take, which is then solved as any take folder
        detected = videos.write_take_folder(take.path, out / "take")
        return {"detected": detected, **_solve_take(out / "take", out, options)}
    return _solve_take(take.path, out, options)


def _solve_take(folder: Path, out: Path, options: Options) -> dict:
    """`mocap solve --take`, and the take's figures: from its report, and against its truth when
    `mocap simulate` wrote one beside it."""
    solved = take_solve.solve(folder, out, options.settings)
    r = solved.report
    statuses = r["solve"]["statuses"]
    figures = {"frames": r["frames"], "cameras": r["cameras"], "imus_used": r["imus_used"],
               "frames_ok": statuses.get("ok", 0) / max(1, sum(statuses.values())),
               "distrusted": sorted(r["solve"]["distrusted"])}
    if (folder / "truth.json").is_file():
        truth = take_truth.score_solved(folder, solved)
        figures["truth"] = {k: round(truth[k], 3) for k in ("joint_centres_pos_cm", "ori_error_offset_removed_deg",
                                                             "sensor_bones_offset_removed_deg")}
    return figures


def _solve_recording(path: Path, out: Path) -> dict:
    """`mocap calibrate --recording` into out/session, then `mocap solve --recording` with that
    session (take.bvh, joints.csv)."""
    report = from_recording.calibrate(path, out / "session")
    with reader.Recording(path) as recording:
        poses, dropped, skeleton = offline.solve_recording(recording, out / "session" / "session.json")
        integrity = recording.integrity
    if not poses:
        raise InputError(f"{path}: no frame could be solved (dropped inputs: {dropped}; the recording: "
                         f"{integrity.describe()})")
    offline.write_poses(poses, skeleton, out / "take.bvh", out / "joints.csv")
    return {"frames": len(poses), "imus_used": len(report["imus_calibrated"]), "dropped": dict(dropped),
            "integrity": integrity.as_dict()}


def _exports(out: Path, formats: tuple[str, ...]) -> dict:
    """Each asked format written as out/take.<suffix> from the solve's BVH or joint CSV."""
    written = {}
    for fmt in formats:
        target = out / f"take{SUFFIXES[fmt]}"
        export(out, fmt, target)
        written[fmt] = target.name
    return written
