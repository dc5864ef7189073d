"""Writes the golden conformance vectors of the IMU nodes' CAN protocol (proto/can).

Each line of can_frames.txt is one frame:

    <Message> <node_id> <identifier, hex> <data, hex> <signal>=<physical value> ...

The bytes are packed here by a minimal little-endian bit packer that shares nothing with
cantools or the code it generates: the layout below is written from the spec's tables
(proto/can/README.md), so a moved, resized or rescaled signal in the database breaks the
vectors. Every implementation must turn the values into exactly these bytes and the bytes
into exactly these values: the hub's side (cantools, tests/test_can_golden.py) and the
node's (firmware/tests/test_can_golden.c). The values are exact at each signal's
resolution. The committed file is the contract: run this only to add vectors, and never
change an existing one.

    python tests/golden/make_can_vectors.py
"""

from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).parent

# message: (base identifier, length in bytes, [(signal, start bit, bits, signed, scale)])
LAYOUT = {
    "Sync": (0x080, 1, [("sync_seq", 0, 8, False, 1)]),
    "ImuQuat": (0x100, 8, [("q_w", 0, 14, True, 2**-13), ("q_x", 14, 14, True, 2**-13),
                           ("q_y", 28, 14, True, 2**-13), ("q_z", 42, 14, True, 2**-13),
                           ("seq", 56, 8, False, 1)]),
    "ImuAccel": (0x140, 8, [("a_x", 0, 15, True, 2**-6), ("a_y", 15, 15, True, 2**-6),
                            ("a_z", 30, 15, True, 2**-6), ("orientation_invalid", 45, 1, False, 1),
                            ("acc_clipped", 46, 1, False, 1), ("mag_disturbed", 47, 1, False, 1),
                            ("sample_time_us", 48, 16, False, 1)]),
    "SyncReport": (0x180, 5, [("sync_seq", 0, 8, False, 1), ("rx_time_us", 8, 32, False, 1)]),
    "CommandReply": (0x580, 8, [("command", 0, 8, False, 1), ("result", 8, 8, False, 1),
                                ("rate_hz", 16, 16, False, 1), ("acc_range_g", 32, 8, False, 1),
                                ("gyro_range_dps", 40, 16, False, 1), ("mode", 56, 1, False, 1),
                                ("running", 57, 1, False, 1)]),
    "Heartbeat": (0x700, 8, [("state", 0, 4, False, 1), ("mode", 4, 1, False, 1),
                             ("synced", 5, 1, False, 1), ("chip", 8, 8, False, 1),
                             ("rate_hz", 16, 16, False, 1)]
                  + [(flag, 32 + i, 1, False, 1) for i, flag in enumerate(
                      ["imu_nack", "mag_nack", "fifo_overflow", "imu_stuck", "mag_stuck",
                       "command_refused", "frame_malformed", "self_test_failed", "acc_clipped",
                       "mag_disturbed", "tx_overflow"])]
                  + [("fw_version_major", 48, 4, False, 1), ("fw_version_minor", 52, 4, False, 1),
                     ("error_count", 56, 8, False, 1)]),
}
# Command is multiplexed by its first byte: the signals each command carries.
COMMAND_SIGNALS = {
    1: [], 2: [], 3: [("rate_hz", 8, 16, False, 1)],
    4: [("acc_range_g", 8, 8, False, 1), ("gyro_range_dps", 16, 16, False, 1)],
    5: [("mode", 8, 8, False, 1)],
}


def pack(length: int, signals, values: dict) -> bytes:
    word = 0
    for name, start, bits, signed, scale in signals:
        raw = round(values.get(name, 0) / scale)
        lo, hi = (-(1 << bits - 1), (1 << bits - 1) - 1) if signed else (0, (1 << bits) - 1)
        assert lo <= raw <= hi and raw * scale == values.get(name, 0), (name, values)
        word |= (raw & ((1 << bits) - 1)) << start
    return word.to_bytes(8, "little")[:length]


def frame(message: str, node_id: int, **values) -> str:
    if message == "Command":
        base, length = 0x600, 8
        signals = [("command", 0, 8, False, 1)] + COMMAND_SIGNALS[values["command"]]
    else:
        base, length, signals = LAYOUT[message]
    assert set(values) <= {s[0] for s in signals}, (message, values)
    full = {s[0]: 0 for s in signals} | values  # every signal of the frame is listed
    identifier = base + (node_id if message != "Sync" else 0)
    data = pack(length, signals, full)
    fields = " ".join(f"{k}={_number(v)}" for k, v in full.items())
    return f"{message} {node_id} {identifier:03X} {data.hex().upper()} {fields}"


def _number(v) -> str:
    return str(int(v)) if float(v).is_integer() else repr(float(v))


def vectors() -> list[str]:
    q = 2**-13
    a = 2**-6
    return [
        frame("Sync", 0, sync_seq=0),
        frame("Sync", 0, sync_seq=201),
        # A sample: ImuQuat then ImuAccel of the same seq.
        frame("ImuQuat", 5, q_w=4096 * q, q_x=-2048 * q, q_y=6000 * q, q_z=-1 * q, seq=17),
        frame("ImuAccel", 5, a_x=12 * a, a_y=-629 * a, a_z=16000 * a, sample_time_us=40961),
        # Extremes: w at +1 clamped to 8191, full-scale negative components, flags set.
        frame("ImuQuat", 63, q_w=8191 * q, q_x=-8192 * q, q_y=0, q_z=8191 * q, seq=255),
        frame("ImuAccel", 63, a_x=-16384 * a, a_y=16383 * a, a_z=0, orientation_invalid=1,
              acc_clipped=1, mag_disturbed=1, sample_time_us=65535),
        frame("ImuQuat", 1, q_w=8191 * q, seq=0),
        frame("ImuAccel", 1, a_z=628 * a, sample_time_us=0),
        frame("SyncReport", 5, sync_seq=201, rx_time_us=4_000_000_123),
        frame("CommandReply", 5, command=3, result=0, rate_hz=120, acc_range_g=16,
              gyro_range_dps=2000, mode=1, running=0),
        frame("CommandReply", 7, command=4, result=4, rate_hz=100, acc_range_g=8,
              gyro_range_dps=1000, mode=0, running=1),
        frame("Heartbeat", 5, state=2, mode=1, synced=1, chip=1, rate_hz=100, fw_version_major=1,
              fw_version_minor=0, error_count=3),
        frame("Heartbeat", 9, state=3, mode=0, synced=0, chip=1, rate_hz=60, imu_nack=1,
              fifo_overflow=1, mag_stuck=1, frame_malformed=1, acc_clipped=1, tx_overflow=1,
              fw_version_major=1, fw_version_minor=0, error_count=255),
        frame("Heartbeat", 2, state=1, mode=1, synced=1, chip=1, rate_hz=200, mag_nack=1,
              imu_stuck=1, command_refused=1, self_test_failed=1, mag_disturbed=1,
              fw_version_major=1, fw_version_minor=0, error_count=0),
        frame("Command", 5, command=1),
        frame("Command", 5, command=2),
        frame("Command", 5, command=3, rate_hz=200),
        frame("Command", 5, command=4, acc_range_g=8, gyro_range_dps=1000),
        frame("Command", 5, command=5, mode=1),
    ]


def main() -> None:
    lines = [line for line in (__doc__ or "").splitlines()[2:5]]
    header = ["# Golden vectors of proto/can/mocap_imu.dbc, written by make_can_vectors.py."]
    header += ["# " + line.strip() for line in lines if line.strip()]
    (HERE / "can_frames.txt").write_text("\n".join(header + vectors()) + "\n")


if __name__ == "__main__":
    main()
