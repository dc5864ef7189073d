"""`mocap solve --take DIR --out OUTDIR`: a take folder (docs/take_format.md) solved
without oracles, by the live host's own input path and solve: the take becomes the messages
its cameras and IMUs would have sent (mocap.takes.messages), the calibration is estimated
from them as from a recording (mocap.calibration.from_messages: the subject chosen per
camera and frame by the host, the first 5 s with enough motion — where the IMUs tilt; the
first 5 s without IMUs — skeleton, keypoint sites, IMU mountings, headings and positions),
then the same messages are solved by the host's pipeline with that calibration, with the
IMUs (E_R, E_P, E_A and the prior), or video only when the take has no IMUs or they never
move enough to calibrate.

Writes OUTDIR/joints.csv (frame, time_s, then <joint>_x, _y, _z in metres in the take's
world frame: joint centres of the solved skeleton), OUTDIR/take.bvh, OUTDIR/skeleton.json,
OUTDIR/imus.json and OUTDIR/layout.json (the estimated calibration in the solver's formats),
OUTDIR/calibration.json + calibration.md (what was estimated, from how many frames) and
OUTDIR/session/ (the calibrated session the take was solved with).
"""
from __future__ import annotations

import csv
import dataclasses
import json
import shutil
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from mocap import _core
from mocap.calibration import from_messages, window
from mocap.errors import InputError
from mocap.io.bvh_export import write_bvh
from mocap.io.session import Session
from mocap.io.take_folder import TakeFolder, read_take
from mocap.model.joint_centres import JOINTS, bone_indices
from mocap.model.solver import distrust_spans, options_from_session, session_solver, solver_options
from mocap.net import wire
from mocap.recording import offline
from mocap.takes import messages as take_messages
from mocap.takes.report import markdown

STATUS_NAMES = {v: k.removeprefix("STATUS_").lower() for k, v in wire.PoseFrame.Status.items()}


@dataclasses.dataclass
class SolvedTake:
    report: dict  # what calibration.json holds
    skeleton: _core.Skeleton  # the estimated one the take was solved with
    thetas: np.ndarray  # (F, 66) at the take's video frames


@dataclasses.dataclass
class Calibrated:
    """A take as the host solves it: its messages and the session calibrated from them."""
    take: TakeFolder
    messages: list[tuple[int, str, bytes]]  # (arrival ns, type name, payload), arrival order
    session: Path  # the calibrated session file (OUTDIR/session/session.json)
    estimated: from_messages.Estimated


def calibrate(folder: Path, out: Path) -> Calibrated:
    """The take's messages, and its session calibrated from them into OUTDIR/session/."""
    take = read_take(folder)
    if take.rig is None:
        raise InputError(f"{folder}: the take has no video; an IMU-only solve needs the IMU calibration from video")
    messages = take_messages.messages(take)
    session = take_messages.write_session(take, out / "session")
    estimated = from_messages.estimate(messages, session, window.SECONDS, str(folder), video_if_still=True)
    from_messages.write_session(out / "session", session, estimated, estimated.report)
    return Calibrated(take, messages, session, estimated)


def solve_take(folder: Path, out: Path, settings: Sequence[str] = ()) -> dict:
    """Solves the take folder into `out`; returns the report (calibration.json). settings:
    solver options ("name=value", "term.field=value") of the solve after the calibration, on
    top of the calibrated session's."""
    return solve(folder, out, settings).report


def solve(folder: Path, out: Path, settings: Sequence[str] = ()) -> SolvedTake:
    """solve_take, also giving the solved poses and the skeleton they are of."""
    calibrated = calibrate(folder, out)
    take, messages, estimated = calibrated.take, calibrated.messages, calibrated.estimated
    if settings:
        _set_solver(calibrated.session, settings)
    pipeline = offline.pipeline_for(calibrated.session)
    thetas, statuses, left_out = _per_frame(offline.solve_messages(pipeline, messages), take)
    skeleton = pipeline.skeleton
    _write_joints(out / "joints.csv", skeleton, thetas, take)
    write_bvh(out / "take.bvh", skeleton, thetas, take.frame_rate)
    imus = [s["name"] for s in json.loads(estimated.imus_json)["imus"]]
    r = estimated.report
    report = {"frames": take.n_frames, "frame_rate": take.frame_rate, "cameras": len(take.rig.cameras),
              "layout": take.layout, "imus_used": len(imus), "imus_not_used_because": r["imus_not_used_because"],
              "window_motion_score_deg": r["window_motion_score_deg"], "skeleton": r["skeleton"],
              "window": r["window"], "dropped": r["dropped"],
              "solve": {"statuses": {s: statuses.count(s) for s in sorted(set(statuses))},
                        "distrusted": distrust_spans(np.arange(take.n_frames) / take.frame_rate, left_out),
                        # the heading tracking's correction at the take's end
                        "heading_change_deg": {n: float(np.degrees(h)) for n, h in zip(imus, pipeline.headings)}}}
    (out / "calibration.json").write_text(json.dumps(report, indent=1))
    for name in ("skeleton.json", "imus.json", "layout.json"):
        shutil.copyfile(out / "session" / name, out / name)
    (out / "calibration.md").write_text(markdown(report))
    return SolvedTake(report, skeleton, thetas)


def _set_solver(path: Path, settings: Sequence[str]) -> None:
    config = Session.load(path)
    options = solver_options(list(settings), base=options_from_session(config.solver))
    dataclasses.replace(config, solver=session_solver(options)).save(path)


def _per_frame(poses: list, take: TakeFolder) -> tuple[np.ndarray, list[str], list[list[str]]]:
    """(F, 66) poses, statuses and sensors left out of the take's video frames, from the solved PoseFrames
    (matched by capture time); InputError when the host solved a different set of frames."""
    times = take_messages.frame_time_ns(take, np.arange(take.n_frames))
    by_time = {p.capture_time_ns: p for p in poses}
    missing = [f for f, t in enumerate(times) if int(t) not in by_time]
    if missing:
        raise InputError(f"the host did not solve {len(missing)} of the take's {take.n_frames} frames "
                         f"(the first: {missing[0]})")
    chosen = [by_time[int(t)] for t in times]
    return (np.array([p.theta for p in chosen]), [STATUS_NAMES[p.status] for p in chosen],
            [list(p.imus_distrusted) for p in chosen])


def _write_joints(path: Path, skel: _core.Skeleton, thetas: np.ndarray, take: TakeFolder) -> None:
    bones = bone_indices(skel.bone_names)
    back = take.world_from_take.T  # ours -> the take's world
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["frame", "time_s", *[f"{j}_{a}" for j in JOINTS for a in "xyz"]])
        for i, theta in enumerate(thetas):
            _, pos = skel.forward_kinematics(theta)
            p = pos[bones] @ back.T
            w.writerow([i, f"{i / take.frame_rate:.6f}", *[f"{v:.6f}" for v in p.reshape(-1)]])
