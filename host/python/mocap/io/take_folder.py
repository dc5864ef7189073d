"""Take folders: a take recorded by other tools, in open formats (docs/take_format.md).

    take.toml      [take] frame_rate, n_frames, world_up_axis, units; [video]; [imu]
    Calib.toml     cameras, Pose2Sim / anipose layout (mocap.io.calib_toml)
    <pose dir>/    OpenPose JSON, one file per frame, per camera
    sensors.csv    sensor, segment, file; one Xsens MT Manager CSV per IMU (mocap.io.xsens_csv)

`read_take` checks everything and raises TakeError (an InputError) naming the file, and
the line and column where there is one; every path it follows must stay inside the take
folder once resolved (symlinks too) and name a regular file or folder, so that a take
never reads a file of the host's (nor echoes one in an error) and a FIFO never blocks it; `write_take` writes the same format. In memory the
world is ours (Z up): a Y-up take's calibration world is rotated by WORLD_FROM_Y_UP.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
import stat
import tomllib
from pathlib import Path

import numpy as np

from mocap import _core
from mocap.errors import InputError, TakeError
from mocap.io import calib_toml, retarget, xsens_csv

LAYOUTS = {"COCO_17": "coco17", "BODY_25B": "body25b", "BLAZEPOSE_33": "blazepose33"}  # file's -> ours
KEYPOINTS = {"coco17": 17, "body25b": 25, "blazepose33": 33}
# Documented body segments -> the bones of host/data/skeleton_default.json.
SEGMENT_BONES = {"head": "head", "upper_back": "spine_upper", "pelvis": "pelvis",
                 **{f"{side}_{seg}": f"{bone}_{side[0]}" for side in ("left", "right")
                    for seg, bone in (("upper_arm", "upper_arm"), ("forearm", "forearm"), ("hand", "hand"),
                                      ("thigh", "thigh"), ("shin", "shin"), ("foot", "foot"))}}
# p_ours = WORLD_FROM_Y_UP @ p_take for world_up_axis = "Y": a rotation (det +1, nothing
# mirrored) taking +Y up to +Z, +Z to +X and +X to +Y (as mocap.io.retarget and Pose2Sim's TRC).
WORLD_FROM_Y_UP = retarget.P
PIXEL_DECIMALS, CONFIDENCE_DECIMALS = 3, 4  # as written in the JSON
# Caps (docs/reliability.md, "Fuzzing"): each file is read whole, and a pose file's people
# are held as (people, keypoints, 3) floats.
MAX_TOML_BYTES = 1 << 20
MAX_POSE_FILE_BYTES = 16 << 20
MAX_PEOPLE = 100  # per pose file (OpenPose finds a crowd's tens)


@dataclasses.dataclass
class ImuRecording:
    sensor: str
    segment: str  # documented segment name
    bone: str  # our skeleton's bone (SEGMENT_BONES)
    times_s: np.ndarray  # (N,) s, take clock: video frame f is at f / frame_rate
    quaternions: np.ndarray  # (N, 4) w, x, y, z: sensor frame -> the sensor's own earth frame (Z up)
    accelerations: np.ndarray  # (N, 3) m/s^2, sensor frame, gravity's reaction included
    packets: np.ndarray | None = None  # (N,) PacketCounter unwrapped (read only)


@dataclasses.dataclass
class TakeFolder:
    frame_rate: float  # Hz
    n_frames: int
    world_up: str = "Z"  # the files' world: "Z" or "Y"; in memory always Z up
    rig: _core.Rig | None = None  # cameras in camera_names order, our Z-up world
    layout: str | None = None  # "coco17", "body25b" or "blazepose33"
    people: list = dataclasses.field(default_factory=list)  # [camera][frame]: (P, K, 3) x, y, confidence
    imus: list = dataclasses.field(default_factory=list)  # ImuRecording
    imu_rate: float | None = None  # Hz, nominal

    @property
    def world_from_take(self) -> np.ndarray:
        """p_ours = world_from_take @ p_in_the_take's_world (for writing results back)."""
        return WORLD_FROM_Y_UP if self.world_up == "Y" else np.eye(3)


class _Toml:
    """take.toml with the line of each key, for located errors."""

    def __init__(self, path: Path):
        self.path = path
        regular_file(path, path)
        try:
            if path.stat().st_size > MAX_TOML_BYTES:
                raise TakeError(path, f"larger than {MAX_TOML_BYTES >> 10} KiB")
            self.text = path.read_text()
            self.data = tomllib.loads(self.text)
        except OSError as e:
            raise TakeError(path, f"cannot read: {e.strerror or e}") from None
        except UnicodeDecodeError as e:
            raise TakeError(path, f"not UTF-8 text (byte {e.start}): not a TOML file") from None
        except tomllib.TOMLDecodeError as e:
            raise TakeError(path, str(e)) from None

    def line(self, table: str, key: str | None = None) -> int | None:
        current = None
        for i, ln in enumerate(self.text.splitlines()):
            head = re.match(r"\s*\[\s*([^\]]+?)\s*\]", ln)
            if head:
                current = head.group(1)
                if key is None and current == table:
                    return i + 1
            elif current == table and key and re.match(rf"\s*{re.escape(key)}\s*=", ln):
                return i + 1
        return None

    def error(self, table: str, key: str | None, message: str) -> TakeError:
        return TakeError(self.path, f"[{table}]{' ' + key if key else ''}: {message}", self.line(table, key))

    def table(self, name: str, required: bool) -> dict | None:
        t = self.data.get(name)
        if t is None and required:
            raise TakeError(self.path, f"no [{name}] table")
        if t is not None and not isinstance(t, dict):
            raise self.error(name, None, "is not a table")
        return t

    def path_of(self, folder: Path, table: str, key: str) -> Path:
        """The path under `[table] key`, refused when it leaves the take folder."""
        return inside(folder, self.get(table, key, str, what="a path"), self.path, f"[{table}] {key}",
                      self.line(table, key))

    def get(self, table: str, key: str, kind, check=lambda v: True, what: str = ""):
        t = self.data[table]
        if key not in t:
            raise self.error(table, None, f"missing key {key}")
        value = t[key]
        ok = isinstance(value, kind) and not isinstance(value, bool) and check(value)
        if not ok:
            raise self.error(table, key, f"{value!r} is not {what or kind}")
        return value


def regular_file(path: Path, where: Path, what: str = "file", line: int | None = None,
                 column: int | None = None, folder: bool = False) -> Path:
    """`path` when it is a regular file (a folder with `folder`); a TakeError at `where`
    otherwise, before anything opens it (a FIFO or a device would block or never end)."""
    try:
        mode = os.stat(path).st_mode
    except OSError as e:
        raise TakeError(where, f"{what} {str(path)!r} not found ({e.strerror})", line, column) from None
    except ValueError:  # a NUL byte: no file has such a name
        raise TakeError(where, f"{what} {str(path)!r} is not a file name (a NUL byte)", line, column) from None
    kind = stat.S_ISDIR(mode) if folder else stat.S_ISREG(mode)
    if not kind:
        raise TakeError(where, f"{what} {str(path)!r} is not a {'folder' if folder else 'regular file'}", line, column)
    return path


def inside(root: Path, name: str, where: Path, what: str, line: int | None = None,
           column: int | None = None) -> Path:
    """`name` relative to the folder of `where` (the file naming it), refused when it leaves the
    take folder `root` once resolved: an absolute path, `..`, or a symlink pointing out."""
    path = where.parent / name
    try:
        resolved, top = path.resolve(), root.resolve()
    except (OSError, RuntimeError, ValueError) as e:  # a symlink loop, a NUL byte
        raise TakeError(where, f"{what} {name!r}: cannot be resolved ({e})", line, column) from None
    if not resolved.is_relative_to(top):
        raise TakeError(where, f"{what} {name!r} is outside the take folder (paths stay inside it)", line, column)
    return path


def _positive(v) -> bool:
    try:
        return 0 < float(v) < math.inf
    except OverflowError:  # an integer beyond float's range
        return False


def _strings(v) -> bool:
    return all(isinstance(s, str) for s in v)


def read_take(folder: str | Path) -> TakeFolder:
    """The take in `folder`, checked; TakeError at the first fault."""
    folder = Path(folder)
    toml = _Toml(inside(folder, "take.toml", folder / "take.toml", "take.toml"))
    toml.table("take", True)
    rate = float(toml.get("take", "frame_rate", (int, float), _positive, "a positive number"))
    n_frames = toml.get("take", "n_frames", int, _positive, "a positive integer")
    up = toml.get("take", "world_up_axis", str, lambda v: v in ("Z", "Y"), '"Z" or "Y"')
    toml.get("take", "units", str, lambda v: v == "m", '"m" (metres: the only unit supported)')
    video, imu = toml.table("video", False), toml.table("imu", False)
    if video is None and imu is None:
        raise TakeError(toml.path, "neither a [video] nor an [imu] table: nothing to solve")
    take = TakeFolder(rate, n_frames, up)
    if video is not None:
        take.rig, take.layout, take.people = _read_video(folder, toml, n_frames, take.world_from_take)
    if imu is not None:
        take.imu_rate = float(toml.get("imu", "rate", (int, float), _positive, "a positive number"))
        take.imus = _read_imus(folder, toml, take.imu_rate)
    return take


def _read_video(folder: Path, toml: _Toml, n_frames: int, world_from_take: np.ndarray):
    calib = toml.path_of(folder, "video", "calibration")
    names = toml.get("video", "camera_names", list, lambda v: len(v) > 0 and _strings(v), "a list of names")
    dirs = toml.get("video", "pose_dirs", list, lambda v: len(v) == len(names) and _strings(v),
                    f"a list of {len(names)} folders (one per camera_names)")
    line = toml.line("video", "pose_dirs")
    paths = [inside(folder, d, toml.path, "pose folder", line) for d in dirs]
    for key, written, values in (("camera_names", names, names), ("pose_dirs", dirs, [p.resolve() for p in paths])):
        twice = [i for i, v in enumerate(values) if v in values[:i]]
        if twice:
            raise toml.error("video", key, f"{written[twice[0]]!r} is named twice (each camera once, its own folder)")
    layout = LAYOUTS.get(toml.get("video", "keypoint_layout", str, lambda v: v in LAYOUTS, " or ".join(LAYOUTS)))
    rig = _rig(calib, names, world_from_take)
    size = None
    if "image_size" in toml.data["video"]:
        size = toml.get("video", "image_size", list, lambda v: len(v) == 2 and all(isinstance(x, int) for x in v),
                        "[width, height] in pixels")
    for cam in rig.cameras if size is not None else []:
        if list(size) != [cam.width, cam.height]:
            raise toml.error("video", "image_size", f"{size} but {calib.name} gives {cam.name} "
                             f"{cam.width} x {cam.height}")
    people = [_read_poses(folder, p, n_frames, KEYPOINTS[layout]) for p in paths]
    return rig, layout, people


def _rig(calib: Path, names: list[str], world_from_take: np.ndarray) -> _core.Rig:
    regular_file(calib, calib, "calibration file")
    try:
        data = calib_toml.read(calib)
        rig = calib_toml.load(calib)
    except InputError as e:
        raise TakeError(calib, str(e).removeprefix(f"{calib}: ")) from None
    keys = [k for k, t in data.items() if k != "metadata" and isinstance(t, dict)]
    cameras = rig.cameras
    cams = []
    for name in names:
        found = [i for i, (key, cam) in enumerate(zip(keys, cameras)) if name in (key, cam.name)]
        if not found:
            raise TakeError(calib, f"no camera {name!r} (take.toml camera_names); it has "
                            f"{', '.join(c.name for c in cameras)}")
        if len(found) > 1:
            raise TakeError(calib, f"camera {name!r} is ambiguous: tables [{keys[found[0]]}] and "
                            f"[{keys[found[1]]}] both answer to it (a key and a name)")
        cam = cameras[found[0]]
        cam.name = name
        cam.rotation = np.asarray(cam.rotation) @ world_from_take.T  # x_cam = R p_take + t = R A^T p_ours + t
        cams.append(cam)
    return _core.Rig(cams)


def _frame_order(path: Path) -> list:
    return [int(p) if p.isdigit() else p for p in re.split(r"(\d+)", path.name)]


def _read_poses(folder: Path, pose_dir: Path, n_frames: int, n_keypoints: int) -> list[np.ndarray]:
    if not pose_dir.is_dir():
        raise TakeError(pose_dir, "pose folder not found (take.toml [video] pose_dirs)")
    files = sorted(pose_dir.glob("*.json"), key=_frame_order)
    if len(files) != n_frames:
        raise TakeError(pose_dir, f"{len(files)} JSON files, but take.toml says n_frames = {n_frames}")
    for f in files:  # a symlink out of the folder, a FIFO: refused before reading
        regular_file(inside(folder, f.name, f, "pose file"), f, "pose file")
    return [_read_pose(f, n_keypoints) for f in files]


def _read_pose(path: Path, n_keypoints: int) -> np.ndarray:
    """(P, K, 3) of one OpenPose JSON file."""
    try:
        if path.stat().st_size > MAX_POSE_FILE_BYTES:
            raise TakeError(path, f"larger than {MAX_POSE_FILE_BYTES >> 20} MiB")
        data = json.loads(path.read_text())
    except json.JSONDecodeError as e:
        raise TakeError(path, f"invalid JSON: {e.msg}", e.lineno, e.colno) from None
    except (OSError, UnicodeDecodeError) as e:
        raise TakeError(path, f"cannot read: {e}") from None
    people = data.get("people") if isinstance(data, dict) else None
    if not isinstance(people, list):
        raise TakeError(path, 'no "people" list')
    if len(people) > MAX_PEOPLE:
        raise TakeError(path, f"{len(people)} people, more than {MAX_PEOPLE}")
    out = np.zeros((len(people), n_keypoints, 3))
    for p, person in enumerate(people):
        values = person.get("pose_keypoints_2d") if isinstance(person, dict) else None
        try:
            out[p] = np.asarray(values, dtype=float).reshape(n_keypoints, 3)
        except (TypeError, ValueError, OverflowError):
            raise TakeError(path, f"people[{p}].pose_keypoints_2d is not {3 * n_keypoints} numbers "
                            f"(x, y, confidence for each of the layout's {n_keypoints} keypoints)") from None
        if not np.isfinite(out[p]).all():
            raise TakeError(path, f"people[{p}].pose_keypoints_2d has a value that is not finite")
    return out


def _read_imus(folder: Path, toml: _Toml, rate: float) -> list[ImuRecording]:
    path = regular_file(toml.path_of(folder, "imu", "sensors"), toml.path, "[imu] sensors", toml.line("imu", "sensors"))
    table = xsens_csv.read_table(path)
    cols = table.index(["sensor", "segment", "file"])
    out, seen = [], set()
    for row, line in zip(table.rows, table.lines):
        sensor, segment, file = (row[c] if c < len(row) else "" for c in cols)
        if not sensor or sensor in seen:
            raise TakeError(path, f"sensor name {sensor!r} is empty or repeated", line, cols[0] + 1)
        if segment not in SEGMENT_BONES:
            raise TakeError(path, f"unknown segment {segment!r} (known: {', '.join(SEGMENT_BONES)})", line, cols[1] + 1)
        imu_path = inside(folder, file, path, "IMU file", line, cols[2] + 1)
        s = xsens_csv.read_imu(regular_file(imu_path, path, "IMU file", line, cols[2] + 1), rate)
        out.append(ImuRecording(sensor, segment, SEGMENT_BONES[segment], s.times_s, s.quaternions, s.accelerations,
                                s.packets))
        seen.add(sensor)
    if not out:
        raise TakeError(path, "no sensors listed", table.header_line)
    return out


def write_take(folder: str | Path, take: TakeFolder) -> None:
    """Writes `take` as a take folder: take.toml, Calib.toml, pose/<camera>/, imu/<sensor>.csv,
    sensors.csv. A Y-up take's calibration is written in its Y-up world."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    lines = ["[take]", f"frame_rate = {take.frame_rate!r}", f"n_frames = {take.n_frames}",
             f'world_up_axis = "{take.world_up}"', 'units = "m"']
    if take.rig is not None:
        lines += _write_video(folder, take)
    if take.imus:
        lines += ["", "[imu]", f"rate = {float(take.imu_rate)!r}", 'sensors = "sensors.csv"']
        _write_imus(folder, take)
    (folder / "take.toml").write_text("\n".join(lines) + "\n")


def _write_video(folder: Path, take: TakeFolder) -> list[str]:
    cams = []
    for cam in _core.Rig.from_json(take.rig.to_json()).cameras:  # a copy: cameras are references
        cam.rotation = np.asarray(cam.rotation) @ take.world_from_take  # back to the take's world
        cams.append(cam)
    (folder / "Calib.toml").write_text(calib_toml.dumps(_core.Rig(cams)))
    names = [c.name for c in cams]
    for name, frames in zip(names, take.people):
        (folder / "pose" / name).mkdir(parents=True, exist_ok=True)
        for f, people in enumerate(frames):
            _write_pose(folder / "pose" / name / f"{name}_{f:012d}_keypoints.json", people)
    layout = next(k for k, v in LAYOUTS.items() if v == take.layout)
    sizes = {(c.width, c.height) for c in cams}
    return ["", "[video]", 'calibration = "Calib.toml"', f"camera_names = {json.dumps(names)}",
            f"pose_dirs = {json.dumps([f'pose/{n}' for n in names])}", f'keypoint_layout = "{layout}"',
            *([f"image_size = {list(sizes.pop())}"] if len(sizes) == 1 else [])]


def _write_pose(path: Path, people: np.ndarray) -> None:
    out = []
    for person in people:
        values = np.column_stack([np.round(person[:, :2], PIXEL_DECIMALS), np.round(person[:, 2], CONFIDENCE_DECIMALS)])
        out.append({"person_id": [-1], "pose_keypoints_2d": [float(v) for v in values.reshape(-1)]})
    path.write_text(json.dumps({"version": 1.3, "people": out}))


def _write_imus(folder: Path, take: TakeFolder) -> None:
    (folder / "imu").mkdir(exist_ok=True)
    rows = ["sensor,segment,file"]
    for s in take.imus:
        xsens_csv.write_imu(folder / "imu" / f"{s.sensor}.csv", s.times_s, s.quaternions, s.accelerations,
                            take.imu_rate)
        rows.append(f"{s.sensor},{s.segment},imu/{s.sensor}.csv")
    (folder / "sensors.csv").write_text("\n".join(rows) + "\n")
