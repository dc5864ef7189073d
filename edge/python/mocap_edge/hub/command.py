"""The hub's two processes: `imu-hub` (the hub on a CAN bus and/or its own I2C bus, publishing
ImuBatch and Health)
and `sim-nodes` (the simulated studio's IMUs as sensor nodes, served over TCP in socketcand's
protocol for a hub's `--can socketcand:...`). Both run until SIGINT/SIGTERM, the hub also
until --duration."""

from __future__ import annotations

import contextlib
import dataclasses
import signal
import sys
import time

import can
import zmq

from mocap.net import transport
from mocap.net.keys import ServerKeys

from mocap_edge.errors import EdgeError
from mocap_edge.hub.can_bus import open_bus
from mocap_edge.hub.i2c import I2cError, I2cImu, open_i2c
from mocap_edge.hub.i2c.filter import FilterLibraryError
from mocap_edge.hub.config import HubConfig
from mocap_edge.hub.hub import Hub
from mocap_edge.hub.service import HubService, publisher
from mocap_edge.hub.sim import socketcand
from mocap_edge.hub.sim.studio import StudioNodes
from mocap_edge.streams import IMU_FIELDS, Streams
from mocap_edge.supervisor import Supervisor


def _stop_on_signals():
    """A stop() that turns true at SIGINT or SIGTERM."""
    stopping: list[bool] = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stopping.append(True))
    return lambda: bool(stopping)


def _turns(stop, supervisor: Supervisor):
    """stop(), which the service asks once per cycle, reporting each cycle to the supervisor."""
    def turn_and_ask() -> bool:
        supervisor.turn()
        return stop()
    return turn_and_ask


def hub(can_uri: str | None, i2c_uri: str | None, config_path: str, bind: str, duration_s: float = 0.0,
        keys: ServerKeys | None = None, supervisor: Supervisor | None = None) -> int:
    config = HubConfig.load(config_path)
    if config.names and not can_uri or config.i2c and not i2c_uri:
        raise EdgeError(f"{config_path} names {'CAN nodes' if config.names and not can_uri else 'I2C IMUs'}: "
                        f"give {'--can' if config.names and not can_uri else '--i2c'}")
    local = _local_imus(config, i2c_uri) if config.i2c else []
    port = open_bus(can_uri) if can_uri else None
    publish, socket = publisher(bind, keys)
    stop = _turns(_stop_on_signals(), supervisor or Supervisor({}))
    service = HubService(port, Hub(config), publish, local=local,
                         reopen=(lambda: open_bus(can_uri)) if can_uri else None)
    try:
        n = service.run(stop, duration_s)
    finally:
        with contextlib.suppress(can.CanError):  # an adapter already gone cannot be closed cleanly
            if service.port is not None:
                service.port.bus.shutdown()
        socket.close()
    i2c = {imu.name: dataclasses.asdict(imu.counts) for imu in local}
    print(f"imu hub: {n} batches sent; nodes {sorted(service.hub.nodes)}; dropped {dict(service.hub.dropped)}; "
          f"bus errors {dict(service.bus_errors.counts)}" + (f"; i2c {i2c}" if i2c else "")
          + (f"; {transport.refused(zmq.Context.instance())} subscribers refused" if keys and keys.allowed else ""),
          file=sys.stderr)
    return 0


def _local_imus(config: HubConfig, uri: str) -> list[I2cImu]:
    """The I2C IMUs of hub.toml on the bus at uri, timed on the shared timebase."""
    try:
        port = open_i2c(uri)
        return [I2cImu(port, address, name, config.rate_hz, config.acc_range_g, config.gyro_range_dps,
                       clock_ns=time.time_ns) for address, name in sorted(config.i2c.items())]
    except (I2cError, FilterLibraryError, ValueError) as e:
        raise EdgeError(f"--i2c {uri}: {e}") from None


def sim_nodes(streams_path: str, config_path: str, port: int, start_ns: int, seed: int = 0,
              unplugged: tuple[str, float, float] | None = None) -> int:
    """Serves the nodes on 127.0.0.1:port; prints `listening PORT` on stdout once it accepts."""
    nodes = StudioNodes(Streams.load(streams_path, read=IMU_FIELDS), HubConfig.load(config_path), start_ns, time.time_ns(), seed,
                        unplugged)
    stop = _stop_on_signals()
    with socketcand.listen(port) as listener:
        print(f"listening {listener.getsockname()[1]}", flush=True)
        counts = socketcand.Server(nodes, listener).run(stop)
    print(f"sim nodes: {counts.frames_sent} frames sent, {counts.frames_received} received, "
          f"{counts.malformed} malformed, {counts.clients} clients", file=sys.stderr)
    return 0
