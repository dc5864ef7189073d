"""An in-process, register-level fake ICM-42688-P that is its own I2C port (bus.I2cPort), for
tests and for ``open_i2c("fake:")``; the sensor side is ``fake_sensor``.

As firmware/tests/support/fake_icm42688.c: WHO_AM_I 0x47, REG_BANK_SEL (banks 0-4), soft
reset (the chip NACKs for 1 ms after it), writes lost for 200 us after a PWR_MGMT0 change
(counted), INT_STATUS cleared by reading, FIFO_COUNT in packets or bytes (latched by reading
COUNTH), FIFO_DATA reads popping bytes (a packet read in part is read again by the next
transfer), FIFO_LOST_PKT, flush. Time: the fake's clock is `clock` (the hub's clock the test
drives); with a :class:`SimClock` every transfer takes bus time (``bus_byte_ns`` per byte,
400 kHz by default) and may start late by ``delay_ns()`` (the kernel scheduling the hub out
between its time stamp and the transfer).

Failures on demand: ``nack(n)`` NACKs the next n transfers, ``absent`` every one (OSError 121,
EREMOTEIO, as i2c-dev raises); ``sensor.stuck`` repeats the last sample.
"""

from __future__ import annotations

import errno
import time
from typing import Callable

from mocap_edge.hub.i2c import regs
from mocap_edge.hub.i2c.fake_sensor import FakeSensor, Motion

BANKS = 5
RESET_NS = 1_000_000  # soft reset: the chip NACKs meanwhile
POWER_WAIT_NS = 200_000  # writes lost after a PWR_MGMT0 change
READ_HEADER_BYTES, WRITE_HEADER_BYTES = 3, 2  # address+W, register (, address+R)
BANK0_DEFAULTS = {regs.REG_INTF_CONFIG0: regs.INTF_CONFIG0_RESET, regs.REG_GYRO_CONFIG0: 0x06,
                  regs.REG_ACCEL_CONFIG0: 0x06, 0x64: 0x10}  # 2000 dps / 16 g at 1 kHz; INT_CONFIG1
READ_ONLY = {regs.REG_INT_STATUS, regs.REG_FIFO_COUNTH, regs.REG_FIFO_COUNTL, regs.REG_FIFO_DATA,
             regs.REG_WHO_AM_I, regs.REG_FIFO_LOST_PKT0, regs.REG_FIFO_LOST_PKT0 + 1}


class SimClock:
    """A simulated clock in ns that the test moves and the fake's bus time advances."""

    def __init__(self, start_ns: int = 0):
        self.now_ns = start_ns

    def __call__(self) -> int:
        return self.now_ns

    def sleep_ns(self, ns: int) -> None:
        self.now_ns += max(0, int(ns))


class FakeIcm42688:
    """The chip at `address` behind its own port, powered on at construction."""

    def __init__(self, clock: Callable[[], int], motion: Motion | None = None, address: int = regs.ADDRESS_AD0_LOW,
                 clock_error: float = 0.0, noise_lsb: float = 0.0, seed: int = 0, bus_byte_ns: int = 22_500,
                 delay_ns: Callable[[], int] | None = None):
        self.clock, self.address, self.bus_byte_ns, self.delay_ns = clock, address, bus_byte_ns, delay_ns
        self.who_am_i = regs.WHO_AM_I_VALUE
        self.registers = [bytearray(128) for _ in range(BANKS)]
        self.sensor = FakeSensor(self.registers[0], motion, clock_error, noise_lsb, seed)
        self.absent, self.nacks_left = False, 0
        self.transfers = self.nacked = self.soft_resets = self.timing_violations = self.protocol_errors = 0
        self.bank, self._busy_until, self._blocked_until = 0, 0, 0
        self._read_offset, self._count_latch = 0, None
        self._reset()

    def nack(self, transfers: int) -> None:
        """NACK the next `transfers` transfers."""
        self.nacks_left = transfers

    # --- bus.I2cPort ---------------------------------------------------------------------
    def read_byte(self, address: int, reg: int) -> int:
        return self.read_block(address, reg, 1)[0]

    def read_block(self, address: int, reg: int, length: int) -> bytes:
        start = self._begin(address)
        out = bytearray()
        for i in range(length):
            self._bus_time(start, READ_HEADER_BYTES + i)
            out.append(self._read(reg))
            if not (self.bank == 0 and reg == regs.REG_FIFO_DATA):
                reg = (reg + 1) & 0x7F
        self._bus_time(start, READ_HEADER_BYTES + length + 1)
        self._read_offset = 0  # a packet read in part is read again from its start
        return bytes(out)

    def write_byte(self, address: int, reg: int, value: int) -> None:
        start = self._begin(address)
        self._bus_time(start, WRITE_HEADER_BYTES + 1)
        self._write(reg & 0x7F, value & 0xFF)

    def sleep_us(self, microseconds: int) -> None:
        if isinstance(self.clock, SimClock):
            self.clock.sleep_ns(microseconds * 1000)
        else:
            time.sleep(microseconds * 1e-6)

    def close(self) -> None:
        pass

    # --- transfers -----------------------------------------------------------------------
    def _begin(self, address: int) -> int:
        if self.delay_ns is not None and isinstance(self.clock, SimClock):
            self.clock.sleep_ns(self.delay_ns())
        self.transfers += 1
        self._count_latch = None
        now = self.clock()
        if address != self.address or self.absent or self.nacks_left > 0 or now < self._busy_until:
            self.nacks_left = max(0, self.nacks_left - 1)
            self.nacked += 1
            raise OSError(errno.EREMOTEIO, "Remote I/O error")
        return now

    def _bus_time(self, start_ns: int, byte_index: int) -> None:
        """The clock to the end of byte `byte_index` of a transfer begun at `start_ns`, the
        chip's samples up to then."""
        if isinstance(self.clock, SimClock):
            self.clock.now_ns = max(self.clock.now_ns, start_ns + byte_index * self.bus_byte_ns)
        self.sensor.advance_to(self.clock())

    # --- registers -----------------------------------------------------------------------
    def _reset(self) -> None:
        for bank in self.registers:
            bank[:] = bytes(128)
        for reg, value in BANK0_DEFAULTS.items():
            self.registers[0][reg] = value
        self.bank = 0
        self.sensor.flush()
        self.sensor.int_status = regs.INT_STATUS_RESET_DONE
        self.sensor.schedule(self.clock())  # sensors off

    def _read(self, reg: int) -> int:
        if reg == regs.REG_BANK_SEL:
            return self.bank
        if self.bank != 0:
            return self.registers[self.bank][reg]
        if reg == regs.REG_INT_STATUS:
            status, self.sensor.int_status = self.sensor.int_status, 0
            return status
        if reg in (regs.REG_FIFO_COUNTH, regs.REG_FIFO_COUNTL):
            return self._read_count(reg)
        if reg == regs.REG_FIFO_DATA:
            return self._pop_byte()
        if reg in (regs.REG_FIFO_LOST_PKT0, regs.REG_FIFO_LOST_PKT0 + 1):
            return (self.sensor.lost_packets >> (8 * (reg - regs.REG_FIFO_LOST_PKT0))) & 0xFF
        if reg == regs.REG_WHO_AM_I:
            return self.who_am_i
        return self.registers[0][reg]

    def _read_count(self, reg: int) -> int:
        if reg == regs.REG_FIFO_COUNTH or self._count_latch is None:
            self._count_latch = self.sensor.fifo_level(self._read_offset)
        big = self.registers[0][regs.REG_INTF_CONFIG0] & regs.INTF_CONFIG0_FIFO_COUNT_BIG
        high = (reg == regs.REG_FIFO_COUNTH) == bool(big)
        return (self._count_latch >> 8) & 0xFF if high else self._count_latch & 0xFF

    def _pop_byte(self) -> int:
        fifo = self.sensor.fifo
        if not fifo:
            return 0xFF
        packet, record = fifo[0]
        byte = packet[self._read_offset]
        self._read_offset += 1
        if self._read_offset == regs.FIFO_PACKET_BYTES:
            fifo.popleft()
            self.sensor.read_log.append(record)
            self._read_offset = 0
        return byte

    def _write(self, reg: int, value: int) -> None:
        now = self.clock()
        if reg == regs.REG_BANK_SEL:
            self.bank = value if value < BANKS else self.bank
            self.protocol_errors += value >= BANKS
        elif now < self._blocked_until:
            self.timing_violations += 1  # the chip ignores writes in this window
        elif self.bank != 0:
            self.registers[self.bank][reg] = value
        elif reg in READ_ONLY:
            self.protocol_errors += 1
        else:
            self._write_bank0(reg, value, now)

    def _write_bank0(self, reg: int, value: int, now: int) -> None:
        bank0, before = self.registers[0], self.registers[0][reg]
        if reg == regs.REG_DEVICE_CONFIG and value & regs.DEVICE_CONFIG_SOFT_RESET:
            self.soft_resets += 1
            self._reset()
            self._busy_until = now + RESET_NS
            return
        if reg == regs.REG_SIGNAL_PATH_RESET:  # self-clearing bits
            if value & regs.SIGNAL_PATH_RESET_FIFO_FLUSH:
                self.sensor.flush()
            return
        bank0[reg] = value
        if reg == regs.REG_PWR_MGMT0 and value != before:
            self._blocked_until = now + POWER_WAIT_NS
            self.sensor.power_changed(before, value, now)
        elif reg == regs.REG_GYRO_CONFIG0 and (value ^ before) & regs.CONFIG0_ODR_MASK:
            self.sensor.schedule(now)
