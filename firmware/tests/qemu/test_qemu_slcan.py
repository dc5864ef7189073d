"""The QEMU node's UART carrying CAN frames as SLCAN: python-can receives them over QEMU's
TCP serial port and cantools decodes them (proto/can/mocap_imu.dbc) to the values the
firmware logged before packing them; commands sent from python-can are answered.
The board: firmware/boards/lm3s6965evb (README.md: what is emulated and what is faked)."""

from __future__ import annotations

import struct
import time
from dataclasses import dataclass

import can
import cantools
import pytest

from mocap.paths import REPO

DBC = REPO / "proto" / "can" / "mocap_imu.dbc"
NODE_ID_BITS = 0x3F  # every base identifier in the DBC is a multiple of 0x40
QUAT_RESOLUTION = 2.0**-13
ACC_RESOLUTION = 2.0**-6
MAG_PATH = "/machine/peripheral/mag"
START, STOP, SET_RATE, SET_RANGES, SET_MODE = 1, 2, 3, 4, 5
OK, UNKNOWN_COMMAND, BAD_LENGTH, BAD_VALUE, BUSY = 0, 1, 2, 3, 4
IDLE, RUNNING = 1, 2


@dataclass
class Frame:
    name: str
    node_id: int
    values: dict
    frame_id: int


@dataclass
class Logged:
    seq: int
    time_us: int
    q_wxyz: tuple[float, ...]
    acc_mps2: tuple[float, ...]
    flags: int


@pytest.fixture(scope="module")
def database():
    return cantools.database.load_file(DBC)


@pytest.fixture
def node(qemu_arm, tmp_path):
    """The QEMU node with the magnetometer on its I2C bus; yields (bus, log path)."""
    image = qemu_arm.board_image("lm3s6965evb", "lm3s6965evb_node")
    log = tmp_path / "node_log.txt"

    def field(qmp):  # uT * 1000; QEMU 7.2 takes no negative value
        for axis, value in zip("xyz", (20000, 0, 40000)):
            qmp.set_property(MAG_PATH, f"mag-{axis}", value)

    qemu, bus = qemu_arm.start_slcan_node(image, log, ["-device", "lsm303dlhc_mag,id=mag,address=0x1e"], field)
    try:
        yield bus, log
    finally:
        bus.shutdown()
        qemu.close()


class Receiver:
    """Frames from the bus decoded with the DBC, every one kept in arrival order."""

    def __init__(self, bus, database) -> None:
        self.bus, self.database = bus, database
        self.frames: list[Frame] = []

    def next(self, wanted: str, timeout_s: float = 5.0) -> Frame:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            message = self.bus.recv(timeout=max(0.0, deadline - time.monotonic()))
            if message is None:
                break
            definition = self.database.get_message_by_frame_id(message.arbitration_id & ~NODE_ID_BITS)
            values = definition.decode(bytes(message.data), decode_choices=False)
            self.frames.append(Frame(definition.name, message.arbitration_id & NODE_ID_BITS, values,
                                     message.arbitration_id))
            if definition.name == wanted:
                return self.frames[-1]
        raise TimeoutError(f"no {wanted} frame within {timeout_s} s")

    def send(self, frame_id: int, data: bytes) -> None:
        self.bus.send(can.Message(arbitration_id=frame_id, data=data, is_extended_id=False))

    def command(self, node_id: int, **signals) -> dict:
        definition = self.database.get_message_by_name("Command")
        self.send(definition.frame_id + node_id, definition.encode(signals, strict=True))
        return self.next("CommandReply").values


def read_log(path) -> list[Logged]:
    def number(word: str) -> float:
        return struct.unpack(">f", bytes.fromhex(word))[0]

    entries = []
    for line in path.read_text().splitlines():
        words = line.split()
        if len(words) == 11 and words[0] == "out":
            entries.append(Logged(int(words[1]), int(words[2]), tuple(number(w) for w in words[3:7]),
                                  tuple(number(w) for w in words[7:10]), int(words[10])))
    return entries


def test_streamed_samples_decode_to_the_values_the_firmware_logged(node, database):
    bus, log = node
    receiver = Receiver(bus, database)
    # Fixture: the node's boot heartbeat (idle, waiting for START).
    heartbeat = receiver.next("Heartbeat")
    node_id = heartbeat.node_id
    assert heartbeat.values["state"] == IDLE
    assert (heartbeat.values["fw_version_major"], heartbeat.values["fw_version_minor"]) == (1, 0)
    # Test: start streaming and receive 60 samples (ImuQuat, then ImuAccel of the same sample).
    assert receiver.command(node_id, command=START)["result"] == OK
    pairs = [(receiver.next("ImuQuat"), receiver.next("ImuAccel")) for _ in range(60)]
    # Assert: each sample equals the firmware's log of it within the signal's resolution.
    logged = {(entry.seq, entry.time_us & 0xFFFF): entry for entry in read_log(log)}
    for quat, accel in pairs:
        assert quat.node_id == node_id and accel.node_id == node_id
        entry = logged[(quat.values["seq"], accel.values["sample_time_us"])]
        decoded_q = [quat.values[name] for name in ("q_w", "q_x", "q_y", "q_z")]
        decoded_a = [accel.values[name] for name in ("a_x", "a_y", "a_z")]
        assert decoded_q == pytest.approx(entry.q_wxyz, abs=QUAT_RESOLUTION)
        assert decoded_a == pytest.approx(entry.acc_mps2, abs=ACC_RESOLUTION / 2)
        flags = (accel.values["orientation_invalid"] | accel.values["acc_clipped"] << 1
                 | accel.values["mag_disturbed"] << 2)
        assert flags == entry.flags
    sequence = [quat.values["seq"] for quat, _ in pairs]
    assert all((b - a) % 256 == 1 for a, b in zip(sequence, sequence[1:]))


def test_commands_are_answered_and_malformed_ones_refused(node, database):
    bus, _ = node
    receiver = Receiver(bus, database)
    node_id = receiver.next("Heartbeat").node_id
    # Test: a sequence of commands, good and bad.
    started = receiver.command(node_id, command=START)
    busy = receiver.command(node_id, command=SET_RATE, rate_hz=50)
    stopped = receiver.command(node_id, command=STOP)
    rate = receiver.command(node_id, command=SET_RATE, rate_hz=50)
    refused_from = len(receiver.frames)
    bad_rate = receiver.command(node_id, command=SET_RATE, rate_hz=500)  # above the 400 Hz the node allows
    receiver.send(0x600 + node_id, bytes([9, 0, 0, 0, 0, 0, 0, 0]))  # no command 9 (cantools refuses it)
    unknown = receiver.next("CommandReply").values
    bus.serialPortOrig.write(b"t6\r")  # a broken SLCAN line: refused by the decoder
    receiver.send(0x600 + node_id, bytes([SET_RATE, 50, 0]))  # a Command of 3 bytes, not 8
    short = receiver.next("CommandReply").values
    restarted = receiver.command(node_id, command=START)
    times = [receiver.next("ImuAccel").values["sample_time_us"] for _ in range(6)]
    heartbeat = receiver.next("Heartbeat", timeout_s=3.0)
    # Assert: each answered with its result and the configuration after it.
    assert (started["result"], started["running"]) == (OK, 1)
    assert busy["result"] == BUSY and busy["rate_hz"] == 100
    assert (stopped["result"], stopped["running"]) == (OK, 0)
    assert (rate["result"], rate["rate_hz"]) == (OK, 50)
    assert bad_rate["result"] == BAD_VALUE and bad_rate["rate_hz"] == 50
    assert unknown["result"] == UNKNOWN_COMMAND
    assert short["result"] == BAD_LENGTH
    assert (restarted["result"], restarted["running"], restarted["rate_hz"]) == (OK, 1, 50)
    steps = [(b - a) % 65536 for a, b in zip(times, times[1:])]
    assert all(abs(step - 20000) < 500 for step in steps), steps
    assert heartbeat.values["state"] == RUNNING and heartbeat.values["rate_hz"] == 50
    # A heartbeat after the refusals reports them (each bit once: since the previous heartbeat).
    after = [frame.values for frame in receiver.frames[refused_from:] if frame.name == "Heartbeat"]
    assert any(values["command_refused"] for values in after)
    assert any(values["frame_malformed"] for values in after)
