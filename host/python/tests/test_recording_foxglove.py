"""A recording carries the skeleton in Foxglove's own schemas beside each PoseFrame: read as
Foxglove reads it (the `mcap` library's reader, each message decoded from the schema's own
descriptors, nothing from generated code), the transforms are the solved joints and the
scene's lines join each bone to its parent."""

import json

import numpy as np
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap.reader import make_reader

from mocap import paths
from mocap.net import wire
from mocap.recording import reader, recorder, recover

PARENTS = {b["name"]: b["parent"] for b in json.loads(paths.DEFAULT_SKELETON.read_text())["bones"]}


def _pose(k: int) -> wire.PoseFrame:
    """A PoseFrame whose joints sit at distinct, known places (the default skeleton's bones)."""
    pose = wire.PoseFrame(capture_time_ns=1_700_000_000_000_000_000 + k * 16_666_667, frame_index=k)
    for b, name in enumerate(PARENTS):
        pose.joints.add(name=name, px=0.1 * b + k, py=-0.05 * b, pz=1.0 + 0.01 * b, qw=np.cos(0.1 * b),
                        qz=np.sin(0.1 * b))
    return pose


def _decoded_as_foxglove_does(path) -> dict[str, list]:
    """topic -> messages of the Foxglove schemas, decoded from the descriptors in the file."""
    pool, added, out = descriptor_pool.DescriptorPool(), set(), {}
    with open(path, "rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=True):
            if not schema.name.startswith("foxglove."):
                continue
            for file in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file:
                if file.name not in added:
                    pool.Add(file)
                    added.add(file.name)
            cls = message_factory.MessageFactory(pool).GetPrototype(pool.FindMessageTypeByName(schema.name))
            out.setdefault(channel.topic, []).append((message.publish_time, cls.FromString(message.data)))
    return out


def test_each_pose_is_a_skeleton_foxglove_can_draw(tmp_path):
    poses = [_pose(k) for k in range(3)]
    with recorder.Recorder(tmp_path / "take.mcap") as rec:
        for k, pose in enumerate(poses):
            assert rec.write(wire.encode(pose), 1_000 + k)
    views = _decoded_as_foxglove_does(tmp_path / "take.mcap")
    assert sorted(views) == ["/skeleton/scene", "/skeleton/transforms"]
    for pose, (publish, transforms), (_, scene) in zip(poses, views["/skeleton/transforms"], views["/skeleton/scene"]):
        assert publish == pose.capture_time_ns
        by_name = {t.child_frame_id: t for t in transforms.transforms}
        assert set(by_name) == set(PARENTS) and {t.parent_frame_id for t in transforms.transforms} == {"world"}
        for j in pose.joints:
            t = by_name[j.name]
            assert (t.translation.x, t.translation.y, t.translation.z) == (j.px, j.py, j.pz)
            assert (t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z) == (j.qw, j.qx, j.qy, j.qz)
        (entity,) = scene.entities
        assert entity.frame_id == "world" and entity.id == "performer" and len(entity.spheres) == len(PARENTS)
        ends = np.array([[p.x, p.y, p.z] for p in entity.lines[0].points]).reshape(-1, 2, 3)
        at = {j.name: np.array([j.px, j.py, j.pz]) for j in pose.joints}
        bones = {(tuple(at[parent]), tuple(at[name])) for name, parent in PARENTS.items() if parent}
        assert {(tuple(a), tuple(b)) for a, b in ends} == bones and len(ends) == len(PARENTS) - 1


def test_the_views_are_left_to_foxglove_and_kept_by_recover(tmp_path):
    with recorder.Recorder(tmp_path / "take.mcap") as rec:
        for k in range(2):
            rec.write(wire.encode(_pose(k)), 1_000 + k)
    assert [m.topic for m in reader.read(tmp_path / "take.mcap")] == ["/pose", "/pose"]  # what solve/replay read
    recover.recover(tmp_path / "take.mcap", tmp_path / "again.mcap")
    assert sorted(_decoded_as_foxglove_does(tmp_path / "again.mcap")) == ["/skeleton/scene", "/skeleton/transforms"]
