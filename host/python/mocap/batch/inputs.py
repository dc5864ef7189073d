"""What a batch is given: take folders, recordings and trials' videos, the names their results get, and the
content hash that says a take was already solved from the same inputs, options and code."""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import os
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

import mocap_edge
from mocap import paths
from mocap.batch import videos
from mocap.errors import InputError
from mocap.takes.export import is_recording
from mocap_edge import resources

TAKE = "take"  # a take folder (docs/take_format.md)
RECORDING = "recording"  # an MCAP recording of a live take (`mocap record`)
VIDEOS = "videos"  # a trial's videos and calibration, to detect first (mocap.batch.videos)
BLOCK = 1 << 20


@dataclasses.dataclass(frozen=True)
class Input:
    path: Path  # absolute: a worker on another machine reads it there (a shared file system)
    kind: str  # TAKE, RECORDING or VIDEOS
    name: str  # its results' folder under the batch's output


def classify(path: Path) -> str:
    """TAKE, RECORDING or VIDEOS; InputError for anything else (checked before any task starts)."""
    if path.is_dir():
        if (path / "take.toml").is_file():
            return TAKE
        if videos.is_trial(path):
            videos.calibration(path)
            return VIDEOS
        raise InputError(f"{path}: neither a take folder (no take.toml, docs/take_format.md) nor a trial's videos "
                         "(no videos/ folder of video files)")
    if path.is_file() and is_recording(path):
        return RECORDING
    if not path.exists():
        raise InputError(f"{path}: no such take folder or recording")
    raise InputError(f"{path}: neither a take folder nor an MCAP recording")


def inputs(given: Sequence[str | Path]) -> list[Input]:
    """The batch's takes, each named after its folder or file; names shared by several takes get
    their parent folder's name in front, then a number."""
    found = [(Path(p).resolve(), classify(Path(p))) for p in given]
    twice = [path for path, n in Counter(path for path, _ in found).items() if n > 1]
    if twice:
        raise InputError(f"{twice[0]}: given twice")
    stems = [p.stem if kind == RECORDING else p.name for p, kind in found]
    names = [f"{p.parent.name}_{s}" if stems.count(s) > 1 else s for (p, _), s in zip(found, stems)]
    unique = [n if names.count(n) == 1 else f"{n}_{names[:i].count(n) + 1}" for i, n in enumerate(names)]
    return [Input(path, kind, name) for (path, kind), name in zip(found, unique)]


def _hash_file(digest, path: Path) -> None:
    with open(path, "rb") as f:
        while block := f.read(BLOCK):
            digest.update(block)


def _files(folder: Path) -> list[Path]:
    """The take folder's regular files, in a fixed order (symbolic links are not followed)."""
    files = []
    for root, dirs, names in os.walk(folder):
        dirs.sort()
        files += [Path(root) / n for n in sorted(names) if (Path(root) / n).is_file()
                  and not (Path(root) / n).is_symlink()]
    return files


def content_hash(take: Input, options: dict) -> str:
    """SHA-256 of the take's bytes (every file of a take folder, with its relative path), the
    batch's options and the code that solves it."""
    digest = hashlib.sha256()
    digest.update(json.dumps({"kind": take.kind, "options": options, "code": code_fingerprint(take.kind)},
                             sort_keys=True).encode())
    if take.kind == RECORDING:
        _hash_file(digest, take.path)
    elif take.kind == VIDEOS:
        for path in [*videos.videos(take.path), videos.calibration(take.path)]:
            digest.update(path.name.encode() + b"\0")
            _hash_file(digest, path)
    else:
        for path in _files(take.path):
            digest.update(str(path.relative_to(take.path)).encode() + b"\0")
            _hash_file(digest, path)
    return digest.hexdigest()


@functools.cache
def code_fingerprint(kind: str) -> str:
    """SHA-256 of the code that solves a take of `kind` as this process runs it (the host's
    modules, compiled bindings, prior and other data files; for videos also the detector's
    modules and weights): a take solved by other code is solved again."""
    roots = [(Path(__file__).resolve().parents[1], (".py", ".so", ".json")), (paths.HOST_DATA, (".py", ".json"))]
    if kind == VIDEOS:
        roots += [(Path(mocap_edge.__file__).parent, (".py",)), (resources.models_dir("blazepose"), (".onnx",))]
    digest = hashlib.sha256()
    for root, suffixes in roots:
        for path in sorted(p for p in root.rglob("*") if p.is_file() and p.suffix in suffixes
                           and not {"__pycache__", "node_modules"} & set(p.relative_to(root).parts)):
            digest.update(str(path.relative_to(root)).encode() + b"\0")
            _hash_file(digest, path)
    return digest.hexdigest()
