"""I2C: the hub's smbus2 driver of a hub-local ICM-42688-P on /dev/i2c-0, the kernel's i2c-stub
answering at 0x68 (AD0 low) with a register file the test preloads: WHO_AM_I, INT_STATUS and
FIFO_COUNT, one FIFO packet. i2c-stub stores what is written and auto-increments a block read:
the FIFO data register reads one packet from 0x30..0x3F (a real chip pops its FIFO there), and
the count stays as written (no data-ready timing). Nothing answers at 0x69: a NACK."""

from __future__ import annotations

import ast
import math
import re
import struct

import pytest
from conftest import START_S, Messages, mocap_edge, sh, stop

BUS, ADDRESS, ABSENT = 0, 0x68, 0x69
ACC, GYR = (1000, -2000, 16384), (16, -32, 1640)  # raw counts written
PACKET = struct.pack(">B6hbH", 0x68, *ACC, *GYR, 25, 1234)  # header: accel + gyro + ODR timestamp
ENDPOINT = "ipc:///tmp/vm-i2c-hub"


# The datasheet's bank-0 register addresses (TDK DS-000347), written here rather than taken
# from the driver's map: a wrong address in the driver must not be written by the test too.
WHO_AM_I, INT_STATUS, FIFO_COUNTH, FIFO_COUNTL, FIFO_DATA = 0x75, 0x2D, 0x2E, 0x2F, 0x30
FIFO_CONFIG, INTF_CONFIG0, PWR_MGMT0, GYRO_CONFIG0, ACCEL_CONFIG0, FIFO_CONFIG1 = 0x16, 0x4C, 0x4E, 0x4F, 0x50, 0x5F


def i2cget(reg: int) -> int:
    """A register read by i2c-tools, not by the code under test."""
    return int(sh("i2cget", "-y", str(BUS), hex(ADDRESS), hex(reg), "b").stdout, 16)


@pytest.fixture(scope="module")
def chip() -> None:
    """i2c-stub's registers preloaded (i2cset) as an ICM-42688-P with one packet in its FIFO."""
    for reg, value in ((WHO_AM_I, 0x47), (INT_STATUS, 0), (FIFO_COUNTH, 0), (FIFO_COUNTL, 1),
                       *((FIFO_DATA + i, b) for i, b in enumerate(PACKET))):
        sh("i2cset", "-y", str(BUS), hex(ADDRESS), hex(reg), hex(value), "b")


def test_the_driver_configures_the_chip_and_converts_its_fifo_packet(chip):
    import time

    from mocap_edge.hub.i2c import open_i2c
    from mocap_edge.hub.i2c.driver import Icm42688, ProbeError
    from mocap_edge.hub.i2c.packets import parse

    driver = Icm42688(open_i2c(f"/dev/i2c-{BUS}"), ADDRESS, odr_hz=1000, acc_range_g=8, gyro_range_dps=1000)
    driver.probe()
    driver.configure()
    # ±1000 °/s and ±8 g (FS_SEL 1), 1 kHz (ODR 6); both sensors low-noise; FIFO streaming packet 3
    # with temperature; FIFO count in records, big-endian, SPI off
    written = {GYRO_CONFIG0: 0x26, ACCEL_CONFIG0: 0x26, PWR_MGMT0: 0x0F, FIFO_CONFIG: 0x40, FIFO_CONFIG1: 0x07,
               INTF_CONFIG0: 0x72}
    assert {hex(reg): hex(i2cget(reg)) for reg in written} == {hex(r): hex(v) for r, v in written.items()}
    assert driver.configured()
    read = driver.read_fifo(time.monotonic_ns)
    assert (read.count, read.lost, read.error, read.data) == (1, 0, None, PACKET)
    packets = parse(read.data, driver.acc_mps2_per_lsb, driver.gyr_rads_per_lsb)
    acc = [v * 8 * 9.80665 / 32768 for v in ACC]  # m/s² at ±8 g
    gyr = [math.radians(v * 1000 / 32768) for v in GYR]  # rad/s at ±1000 °/s
    assert packets.acc_mps2[0].tolist() == pytest.approx(acc, rel=1e-6)
    assert packets.gyr_rads[0].tolist() == pytest.approx(gyr, rel=1e-6)
    sh("i2cset", "-y", str(BUS), hex(ADDRESS), hex(WHO_AM_I), "0x12", "b")  # another chip at the address
    try:
        with pytest.raises(ProbeError, match=f"no ICM-42688-P at I2C address 0x{ADDRESS:02x}: WHO_AM_I read 0x12"):
            driver.probe()
    finally:
        sh("i2cset", "-y", str(BUS), hex(ADDRESS), hex(WHO_AM_I), "0x47", "b")


def test_the_hub_publishes_the_chips_samples_and_names_the_address_that_does_not_answer(chip, tmp_path):
    config = tmp_path / "hub.toml"
    config.write_text(f'[hub]\nrate_hz = 100\n\n[i2c]\n"0x{ADDRESS:02x}" = "pelvis"\n"0x{ABSENT:02x}" = "chest"\n')
    messages = Messages(ENDPOINT)
    hub = mocap_edge("imu-hub", "--i2c", f"/dev/i2c-{BUS}", "--config", str(config), "--bind", ENDPOINT)
    try:
        def samples(got):
            return [s for m in got if type(m).__name__ == "ImuBatch" for s in m.samples]

        def reported(got):
            streams = {s.stream: s for m in got if type(m).__name__ == "Health" for s in m.streams}
            return len(samples(got)) >= 5 and "imu/chest" in streams and streams["imu/chest"].bus_errors >= 2
        done = messages.until(reported, START_S, hub)
    finally:
        err = stop(hub)
        messages.close()
    assert done, f"no samples of pelvis and no chest NACKs reported: {err}"
    assert hub.returncode == 0 and "Traceback" not in err, err
    got = samples(messages.got)
    assert {s.sensor_id for s in got} == {"pelvis"}
    acc = [v * 16 * 9.80665 / 32768 for v in ACC]  # hub.toml's default range: ±16 g
    assert all([s.ax, s.ay, s.az] == pytest.approx(acc, rel=1e-5) for s in got), got[-1]
    assert re.search(rf"chest: 0x{ABSENT:02x}: .* on /dev/i2c-{BUS}: probed again every 1 s", err), err
    counts = ast.literal_eval(re.search(r"; i2c (\{.*\})", err).group(1))
    assert counts["chest"]["nacks"] >= 2 and counts["chest"]["reprobes"] >= 1 and counts["chest"]["samples"] == 0
    assert counts["pelvis"]["nacks"] == 0 and counts["pelvis"]["samples"] > 0


def test_a_bus_that_is_not_there_is_an_error_naming_it():
    from mocap_edge.hub.i2c import I2cError, open_i2c

    with pytest.raises(I2cError, match="/dev/i2c-7: cannot open"):
        open_i2c("/dev/i2c-7")
