"""The ICM-42688-P on the hub's I2C bus, register for register as the firmware's driver
(firmware/drivers/icm42688.c, icm42688_fifo.c) sets it up, but polled: no INT1, no watermark.

Both sensors in low-noise mode at one ODR, the FIFO in stream mode with packet 3 (header,
accel, gyro, temperature, timestamp: 16 bytes), FIFO_COUNT in packets, big-endian. A read
takes INT_STATUS and FIFO_COUNT in one transfer (stamped before and after on the hub's clock:
the sample clock needs both), then the packets counted in bursts of 16. An overflow (FIFO_FULL
with lost packets) flushes the FIFO, as the firmware does: the packets left cannot be placed in
time. Bus errors are ``OSError`` (a NACK: errno 121); the caller counts them.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from mocap_edge.hub.i2c import regs
from mocap_edge.hub.i2c.bus import I2cError, I2cPort

RESET_WAIT_US = 1000  # soft reset to the first access
POWER_WAIT_US = 200  # PWR_MGMT0 change to the next write
POWER_ON = regs.PWR_MGMT0_GYRO_LN | regs.PWR_MGMT0_ACCEL_LN
INTF_CONFIG0 = (regs.INTF_CONFIG0_FIFO_COUNT_REC | regs.INTF_CONFIG0_FIFO_COUNT_BIG | regs.INTF_CONFIG0_DATA_BIG
                | regs.INTF_CONFIG0_SPI_DISABLE)
FIFO_CONFIG1 = regs.FIFO_CONFIG1_TEMP_EN | regs.FIFO_CONFIG1_GYRO_EN | regs.FIFO_CONFIG1_ACCEL_EN
GRAVITY_MPS2, RAD_PER_DEG, FULL_SCALE_LSB = np.float32(9.80665), np.float32(0.017453292519943295), np.float32(32768)


class ProbeError(I2cError):
    """Something answers at the address, but it is not an ICM-42688-P."""


@dataclasses.dataclass
class FifoRead:
    """One read: FIFO_COUNT latched between t0_ns and t1_ns (hub clock), the whole packets read
    (oldest first; fewer than `count` when a burst failed: `error`, the rest stays in the FIFO),
    or `lost` > 0: the FIFO overflowed and was flushed (lost = packets dropped + flushed)."""
    t0_ns: int
    t1_ns: int
    count: int
    data: bytes = b""
    lost: int = 0
    error: OSError | None = None


class Icm42688:
    """One chip at `address` on `port`; configuration as icm42688_config_t (less the watermark)."""

    def __init__(self, port: I2cPort, address: int, odr_hz: int, acc_range_g: int, gyro_range_dps: int):
        if odr_hz not in regs.ODR_CODES or acc_range_g not in regs.ACC_RANGES_G or \
                gyro_range_dps not in regs.GYRO_RANGES_DPS:
            raise I2cError(f"ICM-42688-P: odr_hz {odr_hz} (one of {sorted(regs.ODR_CODES)}), acc_range_g "
                           f"{acc_range_g} (2, 4, 8, 16) or gyro_range_dps {gyro_range_dps} (250 .. 2000) unsupported")
        self.port, self.address, self.odr_hz = port, address, odr_hz
        odr = regs.ODR_CODES[odr_hz]
        self.gyro_config0 = (regs.GYRO_RANGES_DPS.index(gyro_range_dps) << regs.CONFIG0_FS_SHIFT) | odr
        self.accel_config0 = (regs.ACC_RANGES_G.index(acc_range_g) << regs.CONFIG0_FS_SHIFT) | odr
        # float32 as icm42688_set_scales computes them, so the samples equal the node's
        self.acc_mps2_per_lsb = np.float32(acc_range_g) * GRAVITY_MPS2 / FULL_SCALE_LSB
        self.gyr_rads_per_lsb = np.float32(gyro_range_dps) * RAD_PER_DEG / FULL_SCALE_LSB

    def probe(self) -> None:
        """Bank 0 selected and WHO_AM_I checked: ProbeError naming what was read."""
        self.port.write_byte(self.address, regs.REG_BANK_SEL, 0)
        who = self.port.read_byte(self.address, regs.REG_WHO_AM_I)
        if who != regs.WHO_AM_I_VALUE:
            raise ProbeError(f"no ICM-42688-P at I2C address 0x{self.address:02x}: WHO_AM_I read 0x{who:02x}, "
                             f"expected 0x{regs.WHO_AM_I_VALUE:02x}")

    def reset(self) -> None:
        """Soft reset (waits 1 ms), then probe again."""
        self.port.write_byte(self.address, regs.REG_DEVICE_CONFIG, regs.DEVICE_CONFIG_SOFT_RESET)
        self.port.sleep_us(RESET_WAIT_US)
        self.probe()
        self.port.read_byte(self.address, regs.REG_INT_STATUS)  # clears RESET_DONE

    def _settings(self) -> list[tuple[int, int]]:
        return [(regs.REG_GYRO_CONFIG0, self.gyro_config0), (regs.REG_ACCEL_CONFIG0, self.accel_config0),
                (regs.REG_INTF_CONFIG0, INTF_CONFIG0), (regs.REG_FIFO_CONFIG1, FIFO_CONFIG1)]

    def configure(self) -> None:
        """FIFO bypassed, ranges and ODR, FIFO packet 3, sensors on, FIFO streaming, flushed."""
        self.port.write_byte(self.address, regs.REG_FIFO_CONFIG, regs.FIFO_CONFIG_BYPASS)
        for reg, value in self._settings():
            self.port.write_byte(self.address, reg, value)
        if self.port.read_byte(self.address, regs.REG_PWR_MGMT0) != POWER_ON:
            self.port.write_byte(self.address, regs.REG_PWR_MGMT0, POWER_ON)
            self.port.sleep_us(POWER_WAIT_US)  # the gyroscope's first 30 ms read -32768: dropped
        self.port.write_byte(self.address, regs.REG_FIFO_CONFIG, regs.FIFO_CONFIG_STREAM)
        self.port.read_byte(self.address, regs.REG_INT_STATUS)  # stale bits
        self.flush()

    def configured(self) -> bool:
        """The chip still runs our configuration (not reset or power-cycled while unreachable)."""
        expected = self._settings() + [(regs.REG_PWR_MGMT0, POWER_ON), (regs.REG_FIFO_CONFIG, regs.FIFO_CONFIG_STREAM)]
        return all(self.port.read_byte(self.address, reg) == value for reg, value in expected)

    def flush(self) -> None:
        self.port.write_byte(self.address, regs.REG_SIGNAL_PATH_RESET, regs.SIGNAL_PATH_RESET_FIFO_FLUSH)

    def read_fifo(self, clock_ns: Callable[[], int]) -> FifoRead:
        """INT_STATUS and FIFO_COUNT, then the packets counted (class docstring). OSError when the
        first transfer fails (nothing read)."""
        t0 = clock_ns()
        status, high, low = self.port.read_block(self.address, regs.REG_INT_STATUS, 3)
        read = FifoRead(t0, clock_ns(), (high << 8) | low)
        lost = 0
        if status & regs.INT_STATUS_FIFO_FULL:
            lost_bytes = self.port.read_block(self.address, regs.REG_FIFO_LOST_PKT0, 2)
            lost = int.from_bytes(lost_bytes, "little")
        if lost or read.count > regs.FIFO_CAPACITY_SAMPLES:
            self.flush()
            read.lost = lost + min(read.count, regs.FIFO_CAPACITY_SAMPLES)
            return read
        read.data = self._read_packets(read)
        return read

    def _read_packets(self, read: FifoRead) -> bytes:
        chunks, left = [], read.count
        while left > 0:
            n = min(left, regs.READ_BURST_SAMPLES)
            try:
                chunks.append(self.port.read_block(self.address, regs.REG_FIFO_DATA, n * regs.FIFO_PACKET_BYTES))
            except OSError as e:
                read.error = e
                break
            left -= n
        return b"".join(chunks)
