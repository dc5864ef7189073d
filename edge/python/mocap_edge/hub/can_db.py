"""The sensor nodes' CAN messages, read with cantools from the CAN database in proto/can (one
source of truth with the firmware, whose C pack/unpack is generated from the same file).

A node's frames are at the message's base + node id (1..63); a frame is decoded with the
message at `frame_id & ~0x3F`. `decode` never raises anything but CanFrameError, whose
`reason` names the counter to increment: "unknown_id" (no message at that base, an extended
or remote frame), "bad_length" (not the message's length), "bad_node" (node id 0 on a node's
message, or a hub's message from a node).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import cantools

from mocap_edge import resources

NODE_ID_MASK = 0x3F
FROM_HUB = ("Sync", "Command")
STATES = {0: "boot", 1: "idle", 2: "running", 3: "fault"}
COMMANDS = {"start": 1, "stop": 2, "set_rate": 3, "set_ranges": 4, "set_mode": 5}
RESULTS = {0: "ok", 1: "unknown_command", 2: "bad_length", 3: "bad_value", 4: "busy"}


class CanFrameError(ValueError):
    def __init__(self, reason: str, detail: str):
        super().__init__(f"{reason}: {detail}")
        self.reason = reason


@dataclasses.dataclass(frozen=True)
class NodeFrame:
    """A decoded frame of a node: which message, from which node, its signals (physical values)."""
    name: str
    node: int
    signals: dict


class Database:
    def __init__(self, path: Path | None = None, checked: bool = True):
        """path: the CAN database (default mocap_edge.resources.can_database()). checked=False: `encode` skips cantools' range checks (half its cost), for senders whose
        values are already in range (simulated nodes clip theirs as the firmware does)."""
        self.db, self.checked = cantools.database.load_file(str(path or resources.can_database())), checked
        self._by_base = {m.frame_id: m for m in self.db.messages}

    def decode(self, frame_id: int, data: bytes, extended: bool = False, remote: bool = False) -> NodeFrame:
        """A node's frame, checked (see the module docstring)."""
        base, node = frame_id & ~NODE_ID_MASK, frame_id & NODE_ID_MASK
        message = None if extended or remote else self._by_base.get(base)
        if message is None:
            raise CanFrameError("unknown_id", f"0x{frame_id:X}{' extended' if extended else ''}"
                                f"{' remote' if remote else ''}")
        if len(data) != message.length:
            raise CanFrameError("bad_length", f"{message.name} of {len(data)} bytes, not {message.length}")
        if message.name in FROM_HUB or node == 0:
            raise CanFrameError("bad_node", f"{message.name} at 0x{frame_id:X}")
        return NodeFrame(message.name, node, message.decode(bytes(data), decode_choices=False))

    def encode(self, name: str, node: int, **signals) -> tuple[int, bytes]:
        """(frame id, data) of a message to node `node` (Sync: to all, node 0)."""
        message = self.db.get_message_by_name(name)
        if name == "Command":
            signals = {"rate_hz": 0, "acc_range_g": 0, "gyro_range_dps": 0, "mode": 0, **signals}
            data = message.encode(signals, strict=False)
        else:
            data = message.encode(signals, strict=self.checked)
        return message.frame_id + node, bytes(data).ljust(message.length, b"\0")

    def sync(self, sequence: int) -> tuple[int, bytes]:
        return self.encode("Sync", 0, sync_seq=sequence % 256)

    def command(self, node: int, command: str, **arguments) -> tuple[int, bytes]:
        """A Command to `node`: "start", "stop", "set_rate" (rate_hz), "set_ranges"
        (acc_range_g, gyro_range_dps), "set_mode" (mode 0: 6D, 1: 9D)."""
        return self.encode("Command", node, command=COMMANDS[command], **arguments)
