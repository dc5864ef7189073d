"""BVH motion files: parse the hierarchy and motion, and evaluate global joint transforms.

Rotation channels are read in the order the file lists them (never assumed): channels
"Zrotation Yrotation Xrotation" mean R = Rz @ Ry @ Rx. Positions stay in file units.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from mocap.errors import InputError


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

    def global_transforms(self) -> tuple[np.ndarray, np.ndarray]:
        """Global rotations (frames, joints, 3, 3) and positions (frames, joints, 3)."""
        n, nj = self.num_frames, len(self.joints)
        rot = np.zeros((n, nj, 3, 3))
        pos = np.zeros((n, nj, 3))
        col = 0
        for i, j in enumerate(self.joints):
            local_r = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
            local_t = np.broadcast_to(j.offset, (n, 3)).copy()
            for ch in j.channels:
                v = self.values[:, col]
                col += 1
                axis = "XYZ".index(ch[0].upper())
                if ch.lower().endswith("position"):
                    local_t[:, axis] = v  # position channels replace the offset
                else:
                    local_r = local_r @ _axis_rotation(axis, np.radians(v))
            if j.parent < 0:
                rot[:, i] = local_r
                pos[:, i] = local_t
            else:
                rot[:, i] = rot[:, j.parent] @ local_r
                pos[:, i] = pos[:, j.parent] + np.einsum("nij,nj->ni", rot[:, j.parent], local_t)
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


def parse(text: str, source: str = "<bvh>") -> Motion:
    tokens = text.split()
    pos = 0

    def take() -> str:
        nonlocal pos
        if pos >= len(tokens):
            raise InputError(f"{source}: unexpected end of file")
        pos += 1
        return tokens[pos - 1]

    def floats(k: int) -> np.ndarray:
        try:
            return np.array([float(take()) for _ in range(k)])
        except ValueError as e:
            raise InputError(f"{source}: expected {k} numbers: {e}") from None

    if take() != "HIERARCHY":
        raise InputError(f"{source}: not a BVH file (no HIERARCHY)")
    joints: list[Joint] = []
    stack: list[int] = []
    while True:
        tok = take()
        if tok in ("ROOT", "JOINT"):
            name = take()
            if take() != "{":
                raise InputError(f"{source}: expected '{{' after {tok} {name}")
            if take() != "OFFSET":
                raise InputError(f"{source}: expected OFFSET in {name}")
            offset = floats(3)
            channels: list[str] = []
            if tokens[pos] == "CHANNELS":
                take()
                count = int(take())
                channels = [take() for _ in range(count)]
            joints.append(Joint(name, stack[-1] if stack else -1, offset, channels))
            stack.append(len(joints) - 1)
        elif tok == "End":
            take()  # "Site"
            if take() != "{" or take() != "OFFSET":
                raise InputError(f"{source}: malformed End Site")
            end = floats(3)
            if take() != "}":
                raise InputError(f"{source}: malformed End Site")
            if stack:
                joints[stack[-1]].end_site = end
        elif tok == "}":
            if not stack:
                raise InputError(f"{source}: unbalanced braces")
            stack.pop()
        elif tok == "MOTION":
            break
        else:
            raise InputError(f"{source}: unexpected token {tok!r}")
    if stack or not joints:
        raise InputError(f"{source}: hierarchy not closed or empty")
    if take() != "Frames:":
        raise InputError(f"{source}: expected 'Frames:'")
    frames = int(take())
    if take() != "Frame" or take() != "Time:":
        raise InputError(f"{source}: expected 'Frame Time:'")
    frame_time = float(take())
    width = sum(len(j.channels) for j in joints)
    body = tokens[pos:]
    if len(body) < frames * width:
        raise InputError(f"{source}: {len(body) // max(width, 1)} frames present, {frames} declared")
    values = np.asarray(body[: frames * width], dtype=float).reshape(frames, width)
    if not np.isfinite(values).all() or not frame_time > 0:
        raise InputError(f"{source}: non-finite motion values or frame time")
    return Motion(joints, frame_time, values)


def load(path: str | Path) -> Motion:
    return parse(Path(path).read_text(), str(path))
