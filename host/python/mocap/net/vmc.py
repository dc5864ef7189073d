"""Live VMC sender: the solved pose as the VMC protocol (OSC 1.0 over UDP) for Unity EVMC4U,
VSeeFace, VMC4B (Blender) and other "Marionette" receivers (protocol.vmc.info).

One OSC bundle per frame (timetag "immediately") holds:
  /VMC/Ext/OK        (i) 1            a model is loaded: the bone messages are valid
  /VMC/Ext/T         (f) time         sender time, seconds
  /VMC/Ext/Root/Pos  (s) "root" (f) p.x p.y p.z q.x q.y q.z q.w   the avatar root
  /VMC/Ext/Bone/Pos  (s) name   (f) p.x p.y p.z q.x q.y q.z q.w   per bone, local to its parent
Bone names are Unity HumanBodyBones (HUMANOID_BONES); quaternions are (x, y, z, w), positions metres.
A frame of the default skeleton is one 1.75 kB datagram (IP-fragmented on Ethernet, as usual for VMC).

Coordinates: Unity is left-handed, Y up, and a humanoid faces +Z with its left at -X. Our
world is right-handed, Z up, facing +X, left +Y. So v_unity = U v_ours with U = UNITY_FROM_WORLD
(a reflection, det -1), and a rotation R becomes U R U^T (a proper rotation in Unity's axes,
whose quaternion Unity reads with its usual formula).

Rest pose: like a normalised VRM0 rig, every bone frame is aligned with the avatar root in the
T-pose, so local rotations are sent relative to that rest. The root sits on the floor under
the pelvis (our x, y, z=0) with identity rotation; Hips carries the pelvis height and the full
pelvis orientation. Receivers that ignore the root, or bone positions, still get a sensible
avatar. Spine-upper maps to Chest; UpperChest is not sent (optional in Unity's humanoid: an
avatar that has one keeps it at rest). Bones of other skeletons that have no humanoid name are
folded into their nearest mapped descendants.
"""

from __future__ import annotations

import logging
import math
import socket
import struct

import numpy as np

from mocap import rotations

logger = logging.getLogger(__name__)

DEFAULT_PORT = 39539
OSC_IMMEDIATELY = 1  # OSC timetag meaning "process on receipt"
UNITY_FROM_WORLD = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
HUMANOID_BONES = {
    "pelvis": "Hips", "spine_lower": "Spine", "spine_upper": "Chest", "neck": "Neck", "head": "Head",
    **{f"{ours}_{s}": f"{side}{unity}" for s, side in (("l", "Left"), ("r", "Right")) for ours, unity in (
        ("clavicle", "Shoulder"), ("upper_arm", "UpperArm"), ("forearm", "LowerArm"), ("hand", "Hand"),
        ("thigh", "UpperLeg"), ("shin", "LowerLeg"), ("foot", "Foot"), ("toes", "Toes"))},
}


def osc_message(address: str, *args: str | int | float) -> bytes:
    """OSC 1.0 message: address, ',' type tags, then big-endian int32 'i' / float32 'f' / string 's'."""
    tags, payload = ",", b""
    for arg in args:
        if isinstance(arg, str):
            tags, payload = tags + "s", payload + _osc_string(arg)
        elif isinstance(arg, (int, np.integer)):
            tags, payload = tags + "i", payload + struct.pack(">i", arg)
        elif isinstance(arg, (float, np.floating)):
            tags, payload = tags + "f", payload + struct.pack(">f", arg)
        else:
            raise TypeError(f"no OSC type for {type(arg).__name__}")
    return _osc_string(address) + _osc_string(tags) + payload


def osc_bundle(messages: list[bytes], timetag: int = OSC_IMMEDIATELY) -> bytes:
    """OSC 1.0 bundle: '#bundle', a 64-bit NTP timetag, then each element as int32 size + bytes."""
    elements = b"".join(struct.pack(">i", len(m)) + m for m in messages)
    return _osc_string("#bundle") + struct.pack(">Q", timetag) + elements


def _osc_string(text: str) -> bytes:
    """ASCII, NUL-terminated, padded with NULs to a multiple of 4 bytes."""
    raw = text.encode("ascii")
    return raw + b"\0" * (4 - len(raw) % 4)


class VmcSender:
    """Sends poses theta to a VMC receiver over UDP; never raises on a failed send.

    Counters: `sent` datagrams handed to the network, `failures` sends the OS refused
    (no route, bad host, socket closed...), `skipped` frames with a non-finite theta or time, or
    a position or time beyond float32's range (OSC's 'f').
    """

    def __init__(self, skeleton, host: str = "127.0.0.1", port: int = DEFAULT_PORT):
        names, parents = skeleton.bone_names, skeleton.parents
        if names[0] not in HUMANOID_BONES:
            raise ValueError(f"root bone {names[0]!r} has no humanoid name (expected pelvis)")
        self._skeleton = skeleton
        self._address = (host, port)
        self._bones = [(b, HUMANOID_BONES[n], _mapped_ancestor(b, names, parents))
                       for b, n in enumerate(names) if n in HUMANOID_BONES]
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._socket.setblocking(False)  # a full buffer is a counted failure, never a stall
        self.sent = self.failures = self.skipped = 0

    def encode(self, theta, time_s: float) -> bytes:
        """The datagram of one frame (an OSC bundle)."""
        rot, pos = self._skeleton.forward_kinematics(np.asarray(theta, dtype=float))
        root = pos[0] * (1.0, 1.0, 0.0)  # on the floor under the pelvis
        messages = [osc_message("/VMC/Ext/OK", 1), osc_message("/VMC/Ext/T", float(time_s)),
                    _transform("/VMC/Ext/Root/Pos", "root", root, np.eye(3))]
        for b, name, parent in self._bones:
            if parent < 0:
                local_p, local_r = pos[b] - root, rot[b]
            else:
                local_p, local_r = rot[parent].T @ (pos[b] - pos[parent]), rot[parent].T @ rot[b]
            messages.append(_transform("/VMC/Ext/Bone/Pos", name, local_p, local_r))
        return osc_bundle(messages)

    def send(self, theta, time_s: float) -> bool:
        """Send one frame; False (and a counter up) when it was skipped or the send failed."""
        theta = np.asarray(theta, dtype=float)
        if not (np.isfinite(theta).all() and math.isfinite(time_s)):
            self.skipped += 1
            return False
        try:
            packet = self.encode(theta, time_s)
        except OverflowError:  # struct's float32 packing of a value beyond its range
            self.skipped += 1
            return False
        try:
            self._socket.sendto(packet, self._address)
        except OSError as e:
            self.failures += 1
            log = logger.warning if self.failures == 1 else logger.debug
            log("VMC send to %s:%s failed (%d so far): %s", *self._address, self.failures, e)
            return False
        self.sent += 1
        return True

    def close(self) -> None:
        self._socket.close()

    def __enter__(self) -> VmcSender:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _mapped_ancestor(b: int, names: list[str], parents: list[int]) -> int:
    """Nearest ancestor of bone b with a humanoid name; -1 for the root (child of the avatar root)."""
    parent = parents[b]
    while parent >= 0 and names[parent] not in HUMANOID_BONES:
        parent = parents[parent]
    return parent


def _transform(address: str, name: str, position: np.ndarray, rotation: np.ndarray) -> bytes:
    """A VMC transform message from a position and rotation in our frame, sent in Unity's."""
    p = UNITY_FROM_WORLD @ position
    w, x, y, z = rotations.quaternion_from_matrix(UNITY_FROM_WORLD @ rotation @ UNITY_FROM_WORLD.T)
    return osc_message(address, name, *(float(v) for v in (*p, x, y, z, w)))
