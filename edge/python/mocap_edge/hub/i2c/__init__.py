"""IMUs on the hub's own I2C bus: TDK ICM-42688-P chips read through smbus2, their samples
timed on the hub's clock and turned into orientations by the node's own filter (C, ctypes).

``regs`` (the register map, checked against the firmware's header), ``bus`` (the port seam,
smbus2, ``open_i2c``), ``driver`` (probe, configure, FIFO reads), ``packets`` (FIFO packets to
SI units), ``timing`` (each sample's time from the poll times and counts), ``filter`` (the
ctypes binding), ``imu`` (:class:`I2cImu`, all of it behind one ``poll``), and for tests an
in-process fake chip (``fake_chip``, ``fake_sensor``).
"""

from mocap_edge.hub.i2c.bus import I2cError, I2cPort, open_i2c
from mocap_edge.hub.i2c.driver import ProbeError
from mocap_edge.hub.i2c.imu import I2cCounts, I2cImu

__all__ = ["I2cCounts", "I2cError", "I2cImu", "I2cPort", "ProbeError", "open_i2c"]
