"""Each FIFO sample's time on the hub's clock: a line  time = a + period * index  over the
samples written since the FIFO was last flushed, as firmware/core/sample_clock.c fits one on
the node — but the hub has no INT1 edge, only its polls.

What a poll tells: the chip latched FIFO_COUNT = n in a transfer the hub stamped t0 before and
t1 after. Then the newest sample in the FIFO, index k = (samples read before) + n - 1, was
written at or before t1, and sample k + 1 after t0. The chip's oscillator is up to a few %
off nominal, so both the line's offset and its period are fitted:

1. The period: the slope of the widest band the reads leave for the line (the largest
   min(t1 - period * k) - max(t0 - period * (k + 1)); a concave function of the period,
   maximised by golden-section search over MAX_RATE_ERROR about nominal): the linear-programming
   fit that clock_fit uses for the CAN nodes' clocks, here with bounds on both sides. It rests
   on the reads nearest the line, not on their mean, so a read delayed by the hub being
   scheduled out does not move it. Its error is about the band's width (the read's duration)
   over the span of the reads, so the period known before (nominal at first) is kept while the
   reads span fewer samples than the fit that gave it (at least MIN_SPAN): after a restart the
   old period is better than a fit over a few reads.
2. The offset: the line at that period moved to the middle of the band every read allows.
   The band narrows to about the hub's transfer time once polls have fallen at many phases of
   the sample period (they do: the poll interval is not a multiple of the chip's period).

restart() after every flush (configuration, overflow, a corrupt packet): index 0 is the first
sample written after it; the period carries over (the same oscillator). Stamps never go back.

Against the fake chip (edge/python/tests/test_hub_i2c.py: 200 Hz running 2 % fast, polls every
2-18 ms, transfers at 400 kHz starting late by 30 us on average and 0.5-3 ms one time in 50),
a stamp is within 1.5 ms of the true instant in the first second, 0.3 ms up to 4 s, 0.15 ms after.
"""

from __future__ import annotations

import collections

import numpy as np

WINDOW_NS = 10_000_000_000  # reads kept for the fit (as clock_fit: the oscillator wanders slowly)
WINDOW_READS = 1000
MAX_RATE_ERROR = 0.03  # the chip's ODR is within 3 % of nominal (datasheet: +-2 % over temperature)
MIN_SPAN = 20  # samples the reads must span before their slope replaces the period known
SPAN_KEPT = 0.9  # ... and this fraction of the span of the fit that gave that period
SLOPE_EVERY = 10  # reads between fits of the period once it rests on a long span (the offset: every read)
SLOPE_TOLERANCE_NS = 0.01  # per sample
GOLDEN = 0.6180339887498949


class SampleTimer:
    """Times of the samples of one chip's FIFO (module docstring)."""

    def __init__(self, nominal_period_ns: float):
        self.nominal_ns = float(nominal_period_ns)
        self.period_ns = self.nominal_ns  # fitted; carries over restarts
        self.restarts = 0
        self._since_slope = 0  # reads since the period was fitted
        self._period_span = 0  # samples spanned by the reads that gave period_ns
        self._reads: collections.deque[tuple[int, int, int]] = collections.deque()  # (k, t0, t1)
        self._line: tuple[float, float] | None = None  # time(k) = origin + a + period * k
        self._origin = 0
        self._next = 0  # index of the next sample to stamp
        self._last_stamp: int | None = None

    def restart(self) -> None:
        self._reads.clear()
        self._line, self._next = None, 0
        self.restarts += 1

    def observe(self, t0_ns: int, t1_ns: int, count: int) -> None:
        """A read that latched FIFO_COUNT = `count` between t0 and t1 (before its packets are stamped)."""
        if count <= 0:
            return
        self._reads.append((self._next + count - 1, t0_ns, t1_ns))
        while len(self._reads) > WINDOW_READS or t1_ns - self._reads[0][2] > WINDOW_NS:
            self._reads.popleft()
        self._fit()

    def stamp(self, n: int) -> list[int]:
        """The times of the next `n` samples read out (hub ns), oldest first."""
        if self._line is None:
            raise RuntimeError("stamp() before a read was observed")
        a, period = self._line
        times = []
        for k in range(self._next, self._next + n):
            t = self._origin + int(round(a + period * k))
            if self._last_stamp is not None and t <= self._last_stamp:
                t = self._last_stamp + 1
            times.append(t)
            self._last_stamp = t
        self._next += n
        return times

    def _fit(self) -> None:
        reads = np.array(self._reads, dtype=np.int64)
        self._origin = int(reads[-1, 1])
        k = reads[:, 0].astype(float)
        t0, t1 = (reads[:, 1] - self._origin).astype(float), (reads[:, 2] - self._origin).astype(float)
        span = int(k[-1] - k[0])
        self._since_slope += 1
        if span >= max(MIN_SPAN, SPAN_KEPT * self._period_span) and \
                (self._since_slope >= SLOPE_EVERY or span < 2 * self._period_span):
            self.period_ns, self._period_span, self._since_slope = self._band_slope(k, t0, t1), span, 0
        upper = np.min(t1 - self.period_ns * k)  # time(k) <= t1
        lower = np.max(t0 - self.period_ns * (k + 1))  # time(k + 1) > t0
        self._line = (0.5 * (upper + lower), self.period_ns)

    def _band_slope(self, k: np.ndarray, t0: np.ndarray, t1: np.ndarray) -> float:
        """The period of the widest band (module docstring), to SLOPE_TOLERANCE_NS."""
        def width(period: float) -> float:
            return float(np.min(t1 - period * k) - np.max(t0 - period * (k + 1)))

        lo, hi = self.nominal_ns * (1 - MAX_RATE_ERROR), self.nominal_ns * (1 + MAX_RATE_ERROR)
        a, b = hi - GOLDEN * (hi - lo), lo + GOLDEN * (hi - lo)
        wa, wb = width(a), width(b)
        while hi - lo > SLOPE_TOLERANCE_NS:
            if wa < wb:
                lo, a, wa = a, b, wb
                b = lo + GOLDEN * (hi - lo)
                wb = width(b)
            else:
                hi, b, wb = b, a, wa
                a = hi - GOLDEN * (hi - lo)
                wa = width(a)
        return 0.5 * (lo + hi)
