"""The hub's I2C bus as the driver sees it: register reads and writes on a 7-bit address.

:class:`I2cPort` is the seam (the firmware's ``bus.h``): :class:`SmbusPort` is Linux i2c-dev
through smbus2, the fake chip (``fake_chip``) another. A transfer the chip does not
acknowledge raises ``OSError`` with errno EREMOTEIO (121), as the i2c-dev driver does; the
driver counts it and never lets it out of a poll.

``open_i2c(uri)``: ``/dev/i2c-N`` or ``i2c:N`` (smbus2), ``fake:`` (a still fake chip at 0x68
on the monotonic clock, with sensor noise; for trying the hub without hardware).
"""

from __future__ import annotations

import re
import time
from typing import Protocol

from mocap_edge.errors import EdgeError

SMBUS_BLOCK_MAX = 32  # an SMBus I2C-block read: longer ones go through I2C_RDWR


class I2cError(EdgeError):
    """The bus cannot be opened (bad URI, no device, no smbus2), or no chip answers as expected."""


class I2cPort(Protocol):
    """Register access on one I2C bus (addresses 7-bit; multi-byte reads auto-increment, except
    where the chip says otherwise, like a FIFO data register)."""

    def read_byte(self, address: int, reg: int) -> int: ...

    def read_block(self, address: int, reg: int, length: int) -> bytes: ...

    def write_byte(self, address: int, reg: int, value: int) -> None: ...

    def sleep_us(self, microseconds: int) -> None: ...

    def close(self) -> None: ...


class SmbusPort:
    """Linux i2c-dev through smbus2: blocks up to 32 bytes as SMBus I2C-block reads, longer
    ones (FIFO bursts) as one combined write-register + read transfer (I2C_RDWR)."""

    def __init__(self, bus_number: int):
        try:
            import smbus2
        except ImportError as e:
            raise I2cError(f"i2c:{bus_number}: the smbus2 module is missing (pip install smbus2): {e}") from None
        self.name = f"/dev/i2c-{bus_number}"  # in messages
        try:
            self._bus = smbus2.SMBus(bus_number)
        except OSError as e:
            raise I2cError(f"/dev/i2c-{bus_number}: cannot open ({e.strerror}); is i2c-dev loaded?") from None
        self._msg = smbus2.i2c_msg

    def read_byte(self, address: int, reg: int) -> int:
        return self._bus.read_byte_data(address, reg)

    def read_block(self, address: int, reg: int, length: int) -> bytes:
        if length <= SMBUS_BLOCK_MAX:
            return bytes(self._bus.read_i2c_block_data(address, reg, length))
        write, read = self._msg.write(address, [reg]), self._msg.read(address, length)
        self._bus.i2c_rdwr(write, read)
        return bytes(read)

    def write_byte(self, address: int, reg: int, value: int) -> None:
        self._bus.write_byte_data(address, reg, value)

    def sleep_us(self, microseconds: int) -> None:
        time.sleep(microseconds * 1e-6)

    def close(self) -> None:
        self._bus.close()


def _smbus(number: str) -> I2cPort:
    return SmbusPort(int(number))


def _fake(_: str) -> I2cPort:
    from mocap_edge.hub.i2c.fake_chip import FakeIcm42688
    return FakeIcm42688(time.monotonic_ns, noise_lsb=4.0)


# scheme pattern -> opener of the matched group
BACKENDS = {r"/dev/i2c-(\d+)": _smbus, r"i2c:(\d+)": _smbus, r"fake:(.*)": _fake}


def open_i2c(uri: str) -> I2cPort:
    """The port named by `uri` (module docstring); I2cError for anything else."""
    for pattern, opener in BACKENDS.items():
        match = re.fullmatch(pattern, uri)
        if match:
            return opener(match.group(1))
    raise I2cError(f"I2C bus {uri!r}: expected /dev/i2c-N, i2c:N or fake:")
