"""The LSM303DLHC driver read through the lm3s6965evb's real (emulated) I2C master, with
the field injected into QEMU's lsm303dlhc_mag model over QMP (firmware/boards/lm3s6965evb,
mag_probe.c). QEMU's model takes mag-x/y/z in 0.001 uT and refuses negative values."""

from __future__ import annotations

import struct

import pytest

MAG_PATH = "/machine/peripheral/mag"
STATUS_OK, STATUS_NACK = 0, 1
# uT per count of each range code (x and y; z), the datasheet's LSB/gauss: 100 / gain.
GAIN_XY = {1: 1100, 2: 855, 3: 670, 4: 450, 5: 400, 6: 330, 7: 230}
GAIN_Z = {1: 980, 2: 760, 3: 600, 4: 400, 5: 355, 6: 295, 7: 205}


def start_probe(qemu_arm, with_magnetometer: bool):
    image = qemu_arm.board_image("lm3s6965evb", "lm3s6965evb_mag_probe")
    device = ["-device", "lsm303dlhc_mag,id=mag,address=0x1e"] if with_magnetometer else []
    probe = qemu_arm.Qemu("lm3s6965evb", image, device, qmp=True, stdio=True)
    probe.qmp().command("cont")
    assert probe.read_line() == "ready"
    return probe


def command(probe, line: str) -> str:
    probe.send_line(line)
    return probe.read_line()


def read_field(probe) -> tuple[int, list[int], list[float]]:
    """One reading: the driver's status, counts (x y z) and field in uT (x y z)."""
    words = command(probe, "r").split()
    assert words[0] == "mag", words
    counts = [int(word) for word in words[2:5]]
    field_ut = [struct.unpack("<f", bytes.fromhex(word)[::-1])[0] for word in words[5:8]]
    return int(words[1]), counts, field_ut


def inject_ut(probe, field_ut: tuple[float, float, float]) -> None:
    for axis, value in zip("xyz", field_ut):
        probe.qmp().set_property(MAG_PATH, f"mag-{axis}", round(value * 1000))


@pytest.mark.parametrize("range_code", [1, 3, 7])
def test_injected_fields_are_read_in_microtesla(qemu_arm, range_code):
    # Fixture: the probe at range `range_code`; fields chosen inside that range.
    fields_ut = [(0.0, 0.0, 0.0), (21.5, 4.2, 43.0), (60.0, 0.5, 12.25), (150.0, 100.0, 175.0)]
    limit_ut = 2047 * 100 / GAIN_XY[range_code]
    with start_probe(qemu_arm, with_magnetometer=True) as probe:
        assert command(probe, f"g {range_code}") == "ok"
        assert read_field(probe)[0] == STATUS_OK  # configures the chip's gain
        for field_ut in fields_ut:
            expected = [min(value, limit_ut * 0.99) for value in field_ut]
            # Test: inject the field over QMP, read it through the firmware.
            inject_ut(probe, expected)
            status, counts, read_ut = read_field(probe)
            # Assert: equal within one count of the range (QEMU truncates to counts).
            assert status == STATUS_OK
            resolution = [100 / GAIN_XY[range_code], 100 / GAIN_XY[range_code], 100 / GAIN_Z[range_code]]
            for axis in range(3):
                assert abs(read_ut[axis] - expected[axis]) < resolution[axis], (axis, counts, read_ut, expected)
                assert read_ut[axis] == pytest.approx(counts[axis] * resolution[axis], rel=1e-6, abs=1e-9)


def test_an_absent_device_is_reported_and_the_bus_recovers(qemu_arm):
    # Fixture: the magnetometer at 0x1e with a field set.
    with start_probe(qemu_arm, with_magnetometer=True) as probe:
        inject_ut(probe, (30.0, 10.0, 20.0))
        # Test: read at an address where nothing answers, then at the chip's again.
        assert command(probe, "a 1f") == "ok"
        absent = read_field(probe)
        again = read_field(probe)
        assert command(probe, "a 1e") == "ok"
        back = read_field(probe)
        # Assert: NACK reported every time (no hang), then the right field again.
        assert absent[0] == STATUS_NACK and again[0] == STATUS_NACK
        assert back[0] == STATUS_OK
        assert back[2][0] == pytest.approx(30.0, abs=100 / 1100)


def test_no_magnetometer_on_the_bus_is_reported(qemu_arm):
    # Fixture: the board without any I2C device.
    with start_probe(qemu_arm, with_magnetometer=False) as probe:
        # Test: read three times.
        statuses = [read_field(probe)[0] for _ in range(3)]
        # Assert: a NACK each time, and the firmware still answers.
        assert statuses == [STATUS_NACK] * 3
        assert command(probe, "g 2") == "ok"
