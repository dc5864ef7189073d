"""The performer in Foxglove's own schemas (foxglove-schemas-protobuf), recorded beside each
PoseFrame so that a recording opened in Foxglove shows the skeleton in its 3D panel with no
setup:

| topic | schema | content |
|---|---|---|
| /skeleton/transforms | foxglove.FrameTransforms | each bone's frame in "world": its origin (the joint centre) and rotation, as the PoseFrame's joints |
| /skeleton/scene | foxglove.SceneUpdate | entity "performer" in "world": each bone a line from its parent's joint to its own, each joint a sphere |

"world" is ours (right-handed, Z up, metres), the frame Foxglove's 3D panel draws as it is.
The timestamps are the PoseFrame's capture time. Both are derived from the PoseFrame: the
tools that read recordings (solve, calibrate, replay) read only mocap.v1 messages.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path

from foxglove_schemas_protobuf.Color_pb2 import Color
from foxglove_schemas_protobuf.FrameTransforms_pb2 import FrameTransforms
from foxglove_schemas_protobuf.LinePrimitive_pb2 import LinePrimitive
from foxglove_schemas_protobuf.SceneEntity_pb2 import SceneEntity
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from google.protobuf.message import Message
from google.protobuf.timestamp_pb2 import Timestamp

from mocap.net import wire

TRANSFORMS_TOPIC = "/skeleton/transforms"
SCENE_TOPIC = "/skeleton/scene"
TOPICS = (TRANSFORMS_TOPIC, SCENE_TOPIC)
WORLD = "world"
ENTITY = "performer"
JOINT_DIAMETER_M = 0.04
BONE_COLOR = Color(r=0.2, g=0.8, b=1.0, a=1.0)
JOINT_COLOR = Color(r=1.0, g=0.6, b=0.1, a=1.0)


def skeleton_parents(path: str | Path) -> dict[str, str]:
    """bone -> parent bone of a skeleton file (mocap.skeleton/1); the root has none. {} for a
    file that is not one (the scene then has joints and no bones)."""
    try:
        bones = json.loads(Path(path).read_text())["bones"]
        return {b["name"]: b["parent"] for b in bones if b.get("parent")}
    except (OSError, ValueError, KeyError, TypeError):
        return {}


def _timestamp(time_ns: int) -> Timestamp:
    t = max(int(time_ns), 0)
    return Timestamp(seconds=t // 1_000_000_000, nanos=t % 1_000_000_000)


def transforms(pose: wire.PoseFrame) -> FrameTransforms:
    """Each joint of `pose` as a frame of its own in "world"."""
    stamp = _timestamp(pose.capture_time_ns)
    out = FrameTransforms()
    for j in pose.joints:
        t = out.transforms.add(timestamp=stamp, parent_frame_id=WORLD, child_frame_id=j.name)
        t.translation.x, t.translation.y, t.translation.z = j.px, j.py, j.pz
        t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z = j.qw, j.qx, j.qy, j.qz
    return out


def scene(pose: wire.PoseFrame, parents: Mapping[str, str]) -> SceneUpdate:
    """The bones of `pose` as lines (a joint to its parent's, where `parents` knows both) and
    its joints as spheres, one entity replacing the previous frame's."""
    at = {j.name: j for j in pose.joints}
    entity = SceneEntity(timestamp=_timestamp(pose.capture_time_ns), frame_id=WORLD, id=ENTITY)
    lines = entity.lines.add(type=LinePrimitive.LINE_LIST, thickness=3.0, scale_invariant=True, color=BONE_COLOR)
    lines.pose.orientation.w = 1.0
    for name, parent in parents.items():
        if name in at and parent in at:
            for j in (at[parent], at[name]):
                point = lines.points.add()
                point.x, point.y, point.z = j.px, j.py, j.pz
    for j in pose.joints:
        sphere = entity.spheres.add(color=JOINT_COLOR)
        sphere.pose.position.x, sphere.pose.position.y, sphere.pose.position.z = j.px, j.py, j.pz
        sphere.pose.orientation.w = 1.0
        sphere.size.x = sphere.size.y = sphere.size.z = JOINT_DIAMETER_M
    return SceneUpdate(entities=[entity])


def skeleton_messages(pose: wire.PoseFrame, parents: Mapping[str, str]) -> list[tuple[str, Message]]:
    """(topic, message) of what a recording carries beside the PoseFrame."""
    return [(TRANSFORMS_TOPIC, transforms(pose)), (SCENE_TOPIC, scene(pose, parents))]

