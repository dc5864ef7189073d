"""Keypoint layouts as the edge needs them: names (host/data/layouts, shared with the host
solver), each keypoint's left/right twin, and the groups (face, arms, legs) the tracker
checks for left/right swaps — all derived from the names."""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np

from mocap_edge import resources


# Body part of a sided keypoint: the first group with a word in its name (legs before arms:
# "foot_index" is a foot).
GROUP_WORDS = {"face": ("eye", "ear", "mouth", "nose"), "legs": ("hip", "knee", "ankle", "heel", "foot", "toe"),
               "arms": ("shoulder", "elbow", "wrist", "pinky", "index", "thumb", "hand")}


@dataclasses.dataclass(frozen=True)
class Layout:
    name: str
    names: list[str]
    mirror: np.ndarray  # index of each keypoint's left/right twin (itself if none)
    groups: list[np.ndarray]  # sided keypoints per body part

    def __len__(self) -> int:
        return len(self.names)


def _twin(name: str) -> str:
    """left_wrist <-> right_wrist, LEye <-> REye; unchanged when the name has no side."""
    swap = {"left": "right", "right": "left"}
    tokens = name.split("_")
    if any(t in swap for t in tokens):
        return "_".join(swap.get(t, t) for t in tokens)
    if re.match(r"^[LR][A-Z]", name):
        return ("R" if name[0] == "L" else "L") + name[1:]
    return name


def layout(names: list[str], name: str) -> Layout:
    index = {n: i for i, n in enumerate(names)}
    mirror = np.array([index.get(_twin(n), i) for i, n in enumerate(names)])
    sided = [i for i in range(len(names)) if mirror[i] != i]
    part = {i: next((g for g, words in GROUP_WORDS.items() if any(w in names[i].lower() for w in words)), None)
            for i in sided}
    groups = [np.array(g) for g in ([i for i in sided if part[i] == p] for p in GROUP_WORDS) if g]
    return Layout(name, list(names), mirror, groups)


def load(name: str) -> Layout:
    """A layout of host/data/layouts by name ("blazepose33", "coco17", "body25b")."""
    data = json.loads((resources.layouts_dir() / f"{name}.json").read_text())
    return layout([k["name"] for k in data["keypoints"]], data.get("name", name))
