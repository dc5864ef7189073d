"""The IMU hub: timestamps its sensors' samples and publishes them in ImuBatch messages
every `batch_ms` (a CAN or I2C bus read in bursts).

Sources today: a stream file (the simulated studio). The CAN (python-can) and I2C
(smbus2) adapters are the IMU hub issue's."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import zmq

from mocap.net import transport, wire
from mocap_edge import pacing
from mocap_edge.streams import Streams


def batches(streams: Streams, start_ns: int, hub_id: str = "hub0", batch_ms: float = 10.0, bus_ms: float = 1.0,
            stop_sensor: tuple[str, float, float] | None = None) -> Iterator[wire.ImuBatch]:
    """The ImuBatch messages of the IMU streams played from start_ns: one every batch_ms with
    the samples taken up to its end, sent bus_ms later (send_time_ns). stop_sensor (sensor,
    from_s, to_s) silences one sensor for that span (fault drills)."""
    times = start_ns + streams.imu_times_ns.astype(np.int64)
    batch_ns, sequence, s = int(batch_ms * 1e6), 0, 0
    t = int(times[0]) + batch_ns if len(times) else 0
    while s < len(times):
        batch = wire.ImuBatch(hub_id=hub_id, sequence=sequence, send_time_ns=t + int(bus_ms * 1e6))
        while s < len(times) and times[s] <= t:
            rel = streams.imu_times_ns[s] * 1e-9
            for m, sensor in enumerate(streams.imu_ids):
                if stop_sensor and sensor == stop_sensor[0] and stop_sensor[1] <= rel < stop_sensor[2]:
                    continue
                q, a = streams.imu_quaternions[s, m], streams.imu_accelerations[s, m]
                batch.samples.add(sensor_id=sensor, sample_time_ns=int(times[s]), qw=q[0], qx=q[1], qy=q[2],
                                  qz=q[3], ax=a[0], ay=a[1], az=a[2], packet_counter=s % 65536)
            s += 1
        yield batch
        sequence += 1
        t += batch_ns


def run(streams: Streams, endpoint: str, start_ns: int, hub_id: str = "hub0", batch_ms: float = 10.0,
        bus_ms: float = 1.0, stop_sensor: tuple[str, float, float] | None = None) -> int:
    """Plays the IMU streams in real time from start_ns (batches()); returns batches sent."""
    context = zmq.Context.instance()
    socket = transport.publisher(context, endpoint)
    sent = 0
    try:
        for batch in batches(streams, start_ns, hub_id, batch_ms, bus_ms, stop_sensor):
            pacing.sleep_until(batch.send_time_ns)
            socket.send_multipart(wire.encode(batch))
            sent += 1
    finally:
        socket.close(linger=500)
    return sent
