"""One ICM-42688-P on the hub's own I2C bus, as the hub's service loop polls it: the driver
reads the FIFO, the sample timer puts every sample on the hub's clock, the node's filter
(through ctypes) turns them into orientations, and the samples come out at the output rate
as ``ImuSample`` — what a sensor node on CAN would have sent.

As the node does (firmware/core/node_sensors.c): the filter runs at the chip's ODR on every
sample, its gyroscope scaled by the fitted period over the nominal one (the chip's clock is up
to 3 % off); an output every odr / rate samples on average carries the filter's orientation
at that sample and the acceleration averaged since the last output.

Bus trouble never raises out of :meth:`I2cImu.poll`; it is counted (:class:`I2cCounts`):
- a failed transfer (NACK) is counted and the read retried at the next poll; after
  `fail_polls` failed polls in a row the chip is probed again (once per `reprobe_s`): when it
  still runs our configuration (a glitch, not a reset) its FIFO is read on where it stopped,
  else it is reset and configured again (FIFO flushed, the sample timer restarted);
- an overflowed FIFO is flushed; its samples are counted lost (the output counter skips them);
- a chip whose raw samples repeat exactly for more than `stuck_samples` samples (a real one's
  noise never does) is counted stuck and reset;
- invalid packets (empty or unexpected header, a sensor without data) are dropped and counted.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from typing import Callable

import numpy as np

from mocap.net import wire
from mocap_edge.hub.i2c.bus import I2cPort
from mocap_edge.hub.i2c.driver import FifoRead, Icm42688, ProbeError
from mocap_edge.hub.i2c.filter import FLAG_SETTLED, OrientationFilter
from mocap_edge.hub.i2c.packets import Packets, parse
from mocap_edge.hub.i2c.timing import SampleTimer

log = logging.getLogger(__name__)
COUNTER_WRAP = 1 << 16  # ImuSample.packet_counter


@dataclasses.dataclass
class I2cCounts:
    samples: int = 0  # chip samples read and filtered
    published: int = 0  # ImuSamples returned (at the output rate)
    lost: int = 0  # samples lost to FIFO overflows (and flushed with them)
    overflows: int = 0  # FIFO overflows
    nacks: int = 0  # failed transfers (NACK or other bus error)
    reprobes: int = 0  # probes after the first (failed polls in a row, a stuck chip)
    resets: int = 0  # reset and configured again (the first configuration included)
    stuck: int = 0  # times the chip's samples repeated for more than stuck_samples
    invalid: int = 0  # FIFO packets dropped: empty or unexpected header, a -32768 value
    timer_restarts: int = 0  # sample timer started again (after each FIFO flush)


class I2cImu:
    """An ICM-42688-P at `address` on `port` named `sensor_name`, output at `rate_hz` (<= odr_hz),
    its times on `clock_ns` (the hub's clock, the one poll's now_ns comes from)."""

    def __init__(self, port: I2cPort, address: int, sensor_name: str, rate_hz: int, acc_range_g: int = 16,
                 gyro_range_dps: int = 2000, clock_ns: Callable[[], int] = time.monotonic_ns, *, odr_hz: int = 1000,
                 fail_polls: int = 3, reprobe_s: float = 1.0, stuck_samples: int | None = None):
        if not 0 < rate_hz <= odr_hz:
            raise ValueError(f"{sensor_name}: rate_hz {rate_hz} is not 1..odr_hz ({odr_hz})")
        self.chip = Icm42688(port, address, odr_hz, acc_range_g, gyro_range_dps)
        self.name, self.rate_hz, self.odr_hz, self.clock_ns = sensor_name, rate_hz, odr_hz, clock_ns
        self.fail_polls, self.reprobe_ns = fail_polls, int(reprobe_s * 1e9)
        self.stuck_samples = odr_hz if stuck_samples is None else stuck_samples  # 1 s by default
        self.counts = I2cCounts()
        self.last_error: str | None = None  # the latest bus or probe problem, for Health
        self._unanswered: str | None = None  # why the latest probe failed (logged once), None once it answers
        self.timer = SampleTimer(1e9 / odr_hz)
        self.filter = OrientationFilter(1.0 / odr_hz)
        self.running = False  # probed and configured
        self._force_reset = True
        self._probed_once = False
        self._next_probe_ns: int | None = None
        self._failed_polls = 0
        self._last_raw: np.ndarray | None = None
        self._repeats = 0
        self._phase = 0  # output phase: += rate per sample slot, an output each odr
        self._counter = 0  # outputs since start, lost ones included
        self._acc_sum = np.zeros(3)
        self._acc_n = 0
        self._clipped = False

    def poll(self, now_ns: int) -> list[wire.ImuSample]:
        """Reads what the chip has: the outputs due, oldest first (never raises for bus trouble)."""
        if not self.running:
            if self._next_probe_ns is None or now_ns >= self._next_probe_ns:
                self._start(now_ns)
            return []
        try:
            read = self.chip.read_fifo(self.clock_ns)
        except OSError as e:
            self._bus_failed(e, now_ns)
            return []
        self._failed_polls = 0
        if read.lost:
            self._overflowed(read.lost)
            return []
        out = self._consume(read)
        if read.error is not None:
            self._bus_failed(read.error, now_ns)
        return out

    # --- probing -------------------------------------------------------------------------
    def _start(self, now_ns: int) -> None:
        """Probe; resume a chip still configured, else reset and configure it."""
        self.counts.reprobes += self._probed_once
        self._probed_once = True
        try:
            self.chip.probe()
            resume = not self._force_reset and self.chip.configured()
            if not resume:
                self.chip.reset()
                self.chip.configure()
                self._restart_timer()
                self.counts.resets += 1
        except (OSError, ProbeError) as e:
            self.counts.nacks += isinstance(e, OSError)
            error = str(e) if isinstance(e, ProbeError) else f"0x{self.chip.address:02x}: {e}"
            if self._unanswered != error:  # said once, not at every probe
                log.warning("%s: %s on %s: probed again every %g s", self.name, error, self._bus_name(),
                            self.reprobe_ns * 1e-9)
            self.last_error = self._unanswered = error
            self._next_probe_ns = now_ns + self.reprobe_ns
            return
        if self._unanswered is not None:
            log.warning("%s: ICM-42688-P at 0x%02x on %s answers again", self.name, self.chip.address, self._bus_name())
        self.running, self._force_reset, self._failed_polls, self._unanswered = True, False, 0, None
        log.info("%s: ICM-42688-P at 0x%02x %s", self.name, self.chip.address, "resumed" if resume else "configured")

    def _bus_name(self) -> str:
        return getattr(self.chip.port, "name", "the hub's I2C bus")

    def _bus_failed(self, error: OSError, now_ns: int) -> None:
        self.counts.nacks += 1
        self._failed_polls += 1
        self.last_error = f"0x{self.chip.address:02x}: {error}"
        if self._failed_polls >= self.fail_polls:
            self.running, self._next_probe_ns = False, now_ns

    def _restart_timer(self) -> None:
        self.timer.restart()
        self.counts.timer_restarts += 1
        self._last_raw, self._repeats = None, 0

    def _overflowed(self, lost: int) -> None:
        self.counts.overflows += 1
        self.counts.lost += lost
        self._restart_timer()
        self._skip_outputs(lost)

    # --- samples -------------------------------------------------------------------------
    def _consume(self, read: FifoRead) -> list[wire.ImuSample]:
        self.timer.observe(read.t0_ns, read.t1_ns, read.count)
        packets = parse(read.data, self.chip.acc_mps2_per_lsb, self.chip.gyr_rads_per_lsb)
        self.counts.invalid += packets.empty + packets.corrupt + int((~packets.valid).sum())
        n = len(packets.raw)
        times = self.timer.stamp(n) if n else []
        out = []
        for i in range(n):
            if self._stuck(packets.raw[i]):
                break
            out += self._sample(packets, i, times[i])
        if packets.corrupt:
            self.chip.flush()
            self._restart_timer()
        return out

    def _stuck(self, raw: np.ndarray) -> bool:
        """Counts repeats of the raw sample; past stuck_samples: counted, the chip to be reset."""
        same = self._last_raw is not None and np.array_equal(raw, self._last_raw)
        self._repeats = self._repeats + 1 if same else 0
        self._last_raw = raw
        if self._repeats <= self.stuck_samples:
            return False
        self.counts.stuck += 1
        self.last_error = f"0x{self.chip.address:02x}: stuck (raw samples repeat)"
        self.running, self._force_reset, self._next_probe_ns = False, True, None
        return True

    def _sample(self, packets: Packets, i: int, time_ns: int) -> list[wire.ImuSample]:
        """Filters one sample; an output when one is due."""
        due = self._advance_phase()
        if not packets.valid[i]:
            self._counter += due
            return []
        scale = np.float32(self.timer.period_ns / self.timer.nominal_ns)  # as the node: the measured period
        q, flags = self.filter.update(packets.gyr_rads[i] * scale, packets.acc_mps2[i])
        self.counts.samples += 1
        self._acc_sum += packets.acc_mps2[i]
        self._acc_n += 1
        self._clipped |= bool(packets.acc_clipped[i])
        return [self._output(time_ns, q, flags)] if due else []

    def _advance_phase(self) -> bool:
        self._phase += self.rate_hz
        if self._phase < self.odr_hz:
            return False
        self._phase -= self.odr_hz
        return True

    def _skip_outputs(self, samples: int) -> None:
        total = self._phase + samples * self.rate_hz
        self._counter += total // self.odr_hz
        self._phase = total % self.odr_hz

    def _output(self, time_ns: int, q: tuple[float, ...], flags: int) -> wire.ImuSample:
        ax, ay, az = (self._acc_sum / self._acc_n).tolist()
        status = (0 if flags & FLAG_SETTLED else wire.ImuSample.STATUS_ORIENTATION_INVALID) | \
            (wire.ImuSample.STATUS_ACCELERATION_CLIPPED if self._clipped else 0)
        sample = wire.ImuSample(sensor_id=self.name, sample_time_ns=time_ns, qw=q[0], qx=q[1], qy=q[2], qz=q[3],
                                ax=ax, ay=ay, az=az, status=status, packet_counter=self._counter % COUNTER_WRAP)
        self._counter += 1
        self._acc_sum[:] = 0.0
        self._acc_n, self._clipped = 0, False
        self.counts.published += 1
        return sample
