"""BVH motion files: parse the hierarchy and motion, and evaluate global joint transforms.

Rotation channels are read in the order the file lists them (never assumed): channels
"Zrotation Yrotation Xrotation" mean R = Rz @ Ry @ Rx. Positions stay in file units.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from mocap.errors import InputError

MAX_FILE_BYTES = 256 << 20  # a BVH file read whole (the CMU clips are 1-5 MB)
CHANNEL_NAMES = {f"{axis}{kind}".lower() for axis in "XYZ" for kind in ("position", "rotation")}


@dataclasses.dataclass
class Joint:
    name: str
    parent: int  # -1 for the root
    offset: np.ndarray  # (3,), file units
    channels: list[str]
    end_site: np.ndarray | None = None  # offset of an "End Site" child, if any


@dataclasses.dataclass
class Motion:
    joints: list[Joint]
    frame_time: float  # seconds
    values: np.ndarray  # (frames, total channels), degrees and file units

    @property
    def num_frames(self) -> int:
        return self.values.shape[0]

    def index(self, name: str) -> int:
        for i, j in enumerate(self.joints):
            if j.name == name:
                return i
        raise KeyError(name)

    def rest_positions(self) -> np.ndarray:
        """(joints, 3) positions with every channel at zero, file units."""
        pos = np.zeros((len(self.joints), 3))
        for i, j in enumerate(self.joints):
            pos[i] = j.offset + (pos[j.parent] if j.parent >= 0 else 0.0)
        return pos

    def local_transforms(self) -> tuple[np.ndarray, np.ndarray]:
        """Each joint's rotation (frames, joints, 3, 3) and translation (frames, joints, 3) in
        its parent's frame: its channels composed in file order, its offset replaced by its
        position channels."""
        n, nj = self.num_frames, len(self.joints)
        rot = np.broadcast_to(np.eye(3), (n, nj, 3, 3)).copy()
        pos = np.broadcast_to(np.array([j.offset for j in self.joints]), (n, nj, 3)).copy()
        col = 0
        for i, j in enumerate(self.joints):
            for ch in j.channels:
                v = self.values[:, col]
                col += 1
                axis = "XYZ".index(ch[0].upper())
                if ch.lower().endswith("position"):
                    pos[:, i, axis] = v  # position channels replace the offset
                else:
                    rot[:, i] = rot[:, i] @ _axis_rotation(axis, np.radians(v))
        return rot, pos

    def global_transforms(self) -> tuple[np.ndarray, np.ndarray]:
        """Global rotations (frames, joints, 3, 3) and positions (frames, joints, 3)."""
        local_r, local_t = self.local_transforms()
        rot, pos = np.empty_like(local_r), np.empty_like(local_t)
        for i, j in enumerate(self.joints):
            if j.parent < 0:
                rot[:, i], pos[:, i] = local_r[:, i], local_t[:, i]
            else:
                rot[:, i] = rot[:, j.parent] @ local_r[:, i]
                pos[:, i] = pos[:, j.parent] + np.einsum("nij,nj->ni", rot[:, j.parent], local_t[:, i])
        return rot, pos


def _axis_rotation(axis: int, angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    r = np.zeros(angle.shape + (3, 3))
    a, b = [(1, 2), (2, 0), (0, 1)][axis]
    r[..., axis, axis] = 1.0
    r[..., a, a] = c
    r[..., b, b] = c
    r[..., a, b] = -s
    r[..., b, a] = s
    return r


class _Tokens:
    """The whitespace-separated tokens of a BVH file, read in order; InputError at the end."""

    def __init__(self, text: str, source: str):
        self.tokens, self.pos, self.source = text.split(), 0, source

    def take(self) -> str:
        if self.pos >= len(self.tokens):
            raise InputError(f"{self.source}: unexpected end of file")
        self.pos += 1
        return self.tokens[self.pos - 1]

    def peek(self) -> str | None:
        return self.tokens[self.pos] if self.pos < len(self.tokens) else None

    def floats(self, k: int) -> np.ndarray:
        try:
            values = np.array([float(self.take()) for _ in range(k)])
        except ValueError as e:
            raise InputError(f"{self.source}: expected {k} numbers: {e}") from None
        if not np.isfinite(values).all():
            raise InputError(f"{self.source}: expected {k} finite numbers, not {values}")
        return values

    def count(self, what: str, most: int) -> int:
        """A whole number 0..most."""
        token = self.take()
        if not token.isdecimal() or int(token) > most:
            raise InputError(f"{self.source}: {what} {token!r} is not a whole number 0..{most}")
        return int(token)

    def expect(self, *words: str, what: str) -> None:
        if any(self.take() != w for w in words):
            raise InputError(f"{self.source}: {what}")


def _joint(t: _Tokens, keyword: str, parent: int) -> Joint:
    """ROOT or JOINT: name, "{", OFFSET x y z, optional CHANNELS n names."""
    name = t.take()
    t.expect("{", what=f"expected '{{' after {keyword} {name}")
    t.expect("OFFSET", what=f"expected OFFSET in {name}")
    offset = t.floats(3)
    channels: list[str] = []
    if t.peek() == "CHANNELS":
        t.take()
        channels = [t.take() for _ in range(t.count(f"CHANNELS of {name}", 6))]
        if any(c.lower() not in CHANNEL_NAMES for c in channels):
            raise InputError(f"{t.source}: channels of {name} {channels} are not [XYZ]position / [XYZ]rotation")
    return Joint(name, parent, offset, channels)


def _hierarchy(t: _Tokens) -> list[Joint]:
    """The joints, up to and including the MOTION keyword."""
    t.expect("HIERARCHY", what="not a BVH file (no HIERARCHY)")
    joints: list[Joint] = []
    stack: list[int] = []
    while (tok := t.take()) != "MOTION":
        if tok in ("ROOT", "JOINT"):
            joints.append(_joint(t, tok, stack[-1] if stack else -1))
            stack.append(len(joints) - 1)
        elif tok == "End":
            t.take()  # "Site"
            t.expect("{", "OFFSET", what="malformed End Site")
            end = t.floats(3)
            t.expect("}", what="malformed End Site")
            if stack:
                joints[stack[-1]].end_site = end
        elif tok == "}":
            if not stack:
                raise InputError(f"{t.source}: unbalanced braces")
            stack.pop()
        else:
            raise InputError(f"{t.source}: unexpected token {tok!r}")
    if stack or not joints:
        raise InputError(f"{t.source}: hierarchy not closed or empty")
    return joints


def parse(text: str, source: str = "<bvh>") -> Motion:
    t = _Tokens(text, source)
    joints = _hierarchy(t)
    t.expect("Frames:", what="expected 'Frames:'")
    body_size = len(t.tokens) - t.pos
    frames = t.count("Frames:", body_size)  # each frame holds at least one value
    t.expect("Frame", "Time:", what="expected 'Frame Time:'")
    frame_time = t.floats(1)[0]
    width = sum(len(j.channels) for j in joints)
    body = t.tokens[t.pos:]
    if width == 0 or len(body) < frames * width:
        raise InputError(f"{source}: {len(body) // max(width, 1)} frames present, {frames} declared")
    try:
        values = np.asarray(body[: frames * width], dtype=float).reshape(frames, width)
    except ValueError as e:
        raise InputError(f"{source}: motion values: {e}") from None
    if not np.isfinite(values).all() or not frame_time > 0:
        raise InputError(f"{source}: non-finite motion values or frame time")
    return Motion(joints, frame_time, values)


def load(path: str | Path) -> Motion:
    """The BVH file at `path`; InputError when it cannot be read or parsed."""
    try:
        if Path(path).stat().st_size > MAX_FILE_BYTES:
            raise InputError(f"{path}: larger than {MAX_FILE_BYTES >> 20} MiB")
        text = Path(path).read_text()
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{path}: cannot read: {e}") from None
    return parse(text, str(path))
