"""The frame trigger: a master box drives pulses on a GPIO line wired to every camera's
trigger input and to a GPIO input of every box (the master's too); each box timestamps the
rising edges in the kernel (libgpiod v2 edge events, event clock CLOCK_REALTIME, the PTP-
disciplined shared timebase) and gives each captured frame its edge's time and count.

- `TriggerInput`: rising edges as int64 ns; `GpiodTrigger` (a GPIO line) or `FakeTrigger`
  (in-process, deterministic).
- `GpiodTriggerOutput`: the master's pulse train, edges on multiples of the period of the
  shared timebase.
- `TriggerPairing`: frames (capture_time_ns) + edges -> frames carrying the edge's time
  and trigger count. docs/sync.md says why and how accurate.
"""

from __future__ import annotations

import abc
import collections
import dataclasses
import errno
import importlib
import logging
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from types import ModuleType, TracebackType

import numpy as np

from mocap_edge import pacing
from mocap_edge.errors import TriggerError
from mocap_edge.sources.base import Frame

log = logging.getLogger(__name__)


def _gpiod() -> ModuleType:
    try:
        return importlib.import_module("gpiod")
    except ImportError:
        raise TriggerError("the GPIO trigger needs the Python module 'gpiod' (libgpiod v2 bindings, "
                           "pinned in requirements.txt), which is not installed here") from None


def _request_line(chip: str, line: int, settings: object) -> object:
    """gpiod.request_lines with the failures a user can fix turned into TriggerError."""
    gpiod = _gpiod()
    try:
        return gpiod.request_lines(chip, consumer="mocap-trigger", config={line: settings})
    except FileNotFoundError:
        raise TriggerError(f"no GPIO chip at {chip} (gpiodetect lists the chips of this board)") from None
    except (OSError, ValueError) as e:
        if getattr(e, "errno", None) == errno.EBUSY:
            raise TriggerError(f"GPIO line {line} of {chip} is busy: {_holder(gpiod, chip, line)} holds it") from None
        raise TriggerError(f"cannot request GPIO line {line} of {chip}: {e}") from None


def _holder(gpiod: ModuleType, chip: str, line: int) -> str:
    """Who requested the line (its consumer label), as far as the kernel says."""
    try:
        with gpiod.Chip(chip) as opened:
            consumer = opened.get_line_info(line).consumer
    except (OSError, ValueError):
        consumer = None
    return f"the consumer {consumer!r}" if consumer else "another process"


class TriggerInput(abc.ABC):
    """Rising edges of the trigger line in order, as CLOCK_REALTIME ns. `lost_edges` counts
    edges the kernel saw but that were lost before this process read them."""

    lost_edges = 0

    @abc.abstractmethod
    def read_edges(self, timeout_s: float = 0.0) -> list[int]:
        """The edges since the last call; waits up to timeout_s for one if there are none."""

    def close(self) -> None:
        """Releases the line."""

    def __enter__(self) -> TriggerInput:
        return self

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.close()


class GpiodTrigger(TriggerInput):
    """Rising edges of `line` on the GPIO chip `chip` (/dev/gpiochipN), timestamped by the
    kernel's interrupt handler on CLOCK_REALTIME."""

    def __init__(self, chip: str, line: int) -> None:
        gpiod = _gpiod()
        settings = gpiod.LineSettings(direction=gpiod.line.Direction.INPUT, edge_detection=gpiod.line.Edge.RISING,
                                      event_clock=gpiod.line.Clock.REALTIME)
        self._request = _request_line(chip, line, settings)
        self._last_seqno: int | None = None

    def read_edges(self, timeout_s: float = 0.0) -> list[int]:
        if not self._request.wait_edge_events(timeout_s):
            return []
        events = self._request.read_edge_events()
        for event in events:  # the kernel numbers every edge it saw: gaps are edges it lost
            if self._last_seqno is not None:
                self.lost_edges += max(0, event.line_seqno - self._last_seqno - 1)
            self._last_seqno = event.line_seqno
        return [event.timestamp_ns for event in events]

    def close(self) -> None:
        self._request.release()


class GpiodTriggerOutput:
    """The master's pulses on an output line: a rising edge at every multiple of 1 / rate_hz
    of the shared timebase, `pulse_s` high. Software timed, so edges are late by the
    scheduling delay; the boxes timestamp the edge itself, so this only shifts exposures."""

    def __init__(self, chip: str, line: int, rate_hz: float, pulse_s: float = 0.001) -> None:
        gpiod = _gpiod()
        self._value = gpiod.line.Value
        settings = gpiod.LineSettings(direction=gpiod.line.Direction.OUTPUT, output_value=self._value.INACTIVE)
        self._request, self._line = _request_line(chip, line, settings), line
        self.period_ns, self._pulse_ns = round(1e9 / rate_hz), round(pulse_s * 1e9)
        self.skipped = 0  # pulses not sent because this box fell behind

    def run(self, count: int | None = None, stop: threading.Event | None = None) -> int:
        """Pulses until `count` are sent or `stop` is set; returns pulses sent."""
        sent, edge = 0, (time.time_ns() // self.period_ns + 1) * self.period_ns
        while (count is None or sent < count) and not (stop is not None and stop.is_set()):
            pacing.sleep_until(edge)
            self._request.set_value(self._line, self._value.ACTIVE)
            pacing.sleep_until(edge + self._pulse_ns)
            self._request.set_value(self._line, self._value.INACTIVE)
            sent, edge = sent + 1, edge + self.period_ns
            if (behind := time.time_ns() - edge) > 0:
                self.skipped += behind // self.period_ns + 1
                edge += (behind // self.period_ns + 1) * self.period_ns
        return sent

    def close(self) -> None:
        self._request.release()


class FakeTrigger(TriggerInput):
    """Edge k at start_ns + k / rate_hz + a jitter uniform in [-jitter_ns, jitter_ns] (the
    same for the same seed and k), readable once `clock()` has passed it; edges listed in
    `missed` never arrive (a lost interrupt), and `count` ends the train."""

    def __init__(self, rate_hz: float, start_ns: int = 0, jitter_ns: int = 0, missed: Iterable[int] = (),
                 seed: int = 0, count: int | None = None, clock: Callable[[], int] = time.time_ns) -> None:
        self.period_ns = round(1e9 / rate_hz)
        self._start_ns, self._jitter_ns, self._seed, self._count = start_ns, jitter_ns, seed, count
        self._missed, self._clock, self._next = set(missed), clock, 0

    def edge_time(self, k: int) -> int:
        jitter = int(np.random.default_rng([self._seed, k]).integers(-self._jitter_ns, self._jitter_ns + 1))
        return self._start_ns + k * self.period_ns + jitter

    def read_edges(self, timeout_s: float = 0.0) -> list[int]:
        deadline = time.monotonic() + timeout_s
        while True:
            edges, now = [], self._clock()
            while (self._count is None or self._next < self._count) and self.edge_time(self._next) <= now:
                if self._next not in self._missed:
                    edges.append(self.edge_time(self._next))
                self._next += 1
            if edges or time.monotonic() >= deadline:
                return edges
            time.sleep(min(0.001, max(0.0, deadline - time.monotonic())))


@dataclasses.dataclass
class PairingCounts:
    paired: int = 0
    unpaired_frames: int = 0  # no edge within the tolerance: dropped
    unused_edges: int = 0  # no frame claimed them (the camera dropped a frame)
    spurious_edges: int = 0  # less than half a period after the edge before: a glitch, not a trigger


class TriggerPairing:
    """Pairs frames, in capture order, with the edge nearest to capture_time_ns - offset_ns
    within tolerance_ns (default a quarter period); a paired frame takes the edge's time as
    its capture time and the trigger count (edges since the first, missed ones inferred from
    the gaps) as its index; an edge less than half a period after the one before is a glitch
    (a bounce, interference), counted and dropped. A frame whose edge is not read yet waits, up to `max_pending`
    frames; a frame with no edge in its window is dropped and counted."""

    def __init__(self, trigger: TriggerInput, rate_hz: float, tolerance_ns: int | None = None, offset_ns: int = 0,
                 max_pending: int = 4, max_edges: int = 256) -> None:
        self._trigger, self.period_ns = trigger, round(1e9 / rate_hz)
        self.tolerance_ns = self.period_ns // 4 if tolerance_ns is None else tolerance_ns
        self.offset_ns, self.max_pending, self.max_edges = offset_ns, max_pending, max_edges
        self.counts = PairingCounts()
        self._edges: collections.deque[tuple[int, int]] = collections.deque()  # (time ns, trigger count)
        self._pending: collections.deque[Frame] = collections.deque()
        self._last_edge: tuple[int, int] | None = None

    def add(self, frame: Frame) -> list[Frame]:
        """Takes a frame; returns the frames paired now (possibly earlier ones, or none)."""
        self._pending.append(frame)
        self._read_edges()
        return self._resolve(final=False)

    def flush(self) -> list[Frame]:
        """At the end of capture: pairs what can be, counts the rest."""
        self._read_edges()
        paired = self._resolve(final=True)
        self.counts.unused_edges += len(self._edges)
        self._edges.clear()
        return paired

    def pair(self, frames: Iterable[Frame]) -> Iterator[Frame]:
        for frame in frames:
            yield from self.add(frame)
        yield from self.flush()

    def _read_edges(self) -> None:
        for edge in self._trigger.read_edges():
            if self._last_edge is not None and edge - self._last_edge[0] < self.period_ns // 2:
                self.counts.spurious_edges += 1  # neither paired nor counted: the count stays right
                continue
            count = 0 if self._last_edge is None else \
                self._last_edge[1] + max(1, round((edge - self._last_edge[0]) / self.period_ns))
            self._last_edge = (edge, count)
            self._edges.append(self._last_edge)
        while len(self._edges) > self.max_edges:
            self._edges.popleft()
            self.counts.unused_edges += 1

    def _resolve(self, final: bool) -> list[Frame]:
        paired = []
        while self._pending:
            target = self._pending[0].capture_time_ns - self.offset_ns
            while self._edges and self._edges[0][0] < target - self.tolerance_ns:  # too early for any frame
                self._edges.popleft()
                self.counts.unused_edges += 1
            window = [e for e in self._edges if e[0] <= target + self.tolerance_ns]
            if window:
                edge = min(window, key=lambda e: abs(e[0] - target))
                while self._edges.popleft() != edge:
                    self.counts.unused_edges += 1
                frame = self._pending.popleft()
                paired.append(dataclasses.replace(frame, index=edge[1], capture_time_ns=edge[0]))
                self.counts.paired += 1
            elif self._edges or final or len(self._pending) > self.max_pending:
                # a later edge was read (edges come in order), or the wait is over
                frame = self._pending.popleft()
                self.counts.unpaired_frames += 1
                log.debug("frame %d (capture %d ns) has no trigger edge within %d ns: dropped", frame.index,
                          frame.capture_time_ns, self.tolerance_ns)
            else:
                break  # its edge may not have been read yet
        return paired
