"""A sensor node's clock on the hub's: hub_ns = offset + rate · node_us, fitted online from the
two-step synchronisation of the CAN protocol (proto/can/README.md, "Time synchronisation").

The hub sends `Sync` and keeps its transmit time; the node answers with the Sync's arrival on
its 32-bit microsecond timer. A Sync reaches the node *after* the hub stamped it (queuing in
the driver and behind a frame on the bus; the node's interrupt latency), never before: every
pair (node time, hub time) lies on or below the true line, by its delay. So the line is
fitted to the pairs' upper envelope — the line above every pair that passes nearest them, which
touches the upper convex hull at the pairs' mean node time (the linear-programming estimator of
network clock synchronisation: Moon, Skelly and Towsley, INFOCOM 1999). Its error is that of
the least-delayed pairs, not their mean delay: with delays uniform in 0-0.5 ms and 10 Syncs a
second it is tens of microseconds after 2 s and a few after 10 s (`make bench`, "hub").

The fit uses the pairs of the last `window_s` (the node's oscillator wanders), unwraps the
node's 32-bit timer (71.6 minutes) by the fit's own prediction, and starts again when a node's
time jumps away from the prediction (the node rebooted: its timer restarted). Mapped times
never go backwards: a node's sample mapped before the one mapped before it (a new fit moved the
line) is held at that one plus a nanosecond, and counted. Beyond 400 pairs the line is
refitted once a twentieth of them is new (every 0.5 s at 100 Syncs a second over 10 s), not
at every pair: a fit costs the number of pairs, and the line then moves by far less than its
error in between. (Refitting that sparsely from the start costs the first seconds' accuracy:
p99 29 µs instead of 17 µs at 2-3 s, `make bench`.)
"""

from __future__ import annotations

import dataclasses

import numpy as np

WRAP_US = 1 << 32  # the node's timer
# A reported time this far from the fit's prediction: the node restarted (a timer that started
# again from 0). Generous: a link with long queues (an SLCAN adapter, the emulator's UART)
# delays some pairs by hundreds of milliseconds; the timer wraps only every 71.6 minutes.
REBOOT_JUMP_US = 1_000_000.0
PRUNE_MARGIN_NS = 200_000.0  # pairs this far below the previous line's top are not hull candidates
REFIT_EVERY_PAIR = 400  # up to this many pairs the line is refitted at each; beyond, once
REFIT_FRACTION = 0.05  # this fraction of them is new


@dataclasses.dataclass
class ClockStats:
    pairs: int = 0  # Sync pairs used since the last restart
    restarts: int = 0  # fits started again (the node's timer jumped: a reboot)
    held: int = 0  # mapped times held so as not to go backwards


def upper_envelope_line(x: np.ndarray, y: np.ndarray, slope: float | None = None,
                        margin: float = np.inf) -> tuple[float, float]:
    """(a, b) of y = a + b·x, the line on or above every point that minimises the summed
    distance to them: the upper hull's edge at m = mean(x). At least two distinct x.

    That line minimises f(b) = max_i (y_i - b·(x_i - m)), whose terms rise with b for the
    points left of m (L) and fall for those right of it (R): f is lowest where the two maxima
    cross, at b = min over i in L of max over j in R of the slope from i to j — one array
    operation over L × R instead of a hull walked in Python.

    With the previous fit's `slope`, points more than `margin` below the highest line of that
    slope are left out first (the mean stays that of all points). The line from the rest is the
    answer when every point lies on or below it (then no left-out point could have lowered f);
    else — the previous slope was further off than margin / span allows, as early fits from a
    few pairs can be — the line is fitted to all of them."""
    if np.ptp(x) == 0:
        raise ValueError("the points have one x: no line")
    mean = float(x.mean())
    if slope is not None and np.isfinite(margin):
        r = y - slope * x
        keep = r >= r.max() - margin
        line = _min_max_line(x[keep], y[keep], mean)
        if line is not None and (y - line[1] * x).max() <= line[0] + 1e-9 * float(np.abs(y).max()) + 1e-3:
            return line
    line = _min_max_line(x, y, mean)
    assert line is not None  # two distinct x: some on each side of their mean
    return line


def _min_max_line(x: np.ndarray, y: np.ndarray, mean: float) -> tuple[float, float] | None:
    right = x > mean
    left = ~right
    if not right.any() or not left.any():
        return None
    slopes = (y[right][None, :] - y[left][:, None]) / (x[right][None, :] - x[left][:, None])
    b = float(slopes.max(axis=1).min())
    return float((y - b * x).max()), b


class _Pairs:
    """(node µs, hub ns) pairs in arrival order, in arrays (a fit reads them all: no conversion
    from Python objects); the oldest leave from the front."""

    def __init__(self, capacity: int = 1024):
        self._x, self._y = np.zeros(capacity), np.zeros(capacity, dtype=np.int64)
        self._start = self._end = 0

    def __len__(self) -> int:
        return self._end - self._start

    def append(self, node_us: float, hub_ns: int) -> None:
        if self._end == len(self._x):  # full at the back: move the live pairs to the front, or grow
            n = len(self)
            if n > len(self._x) // 2:
                self._x, self._y = np.resize(self._x, 2 * len(self._x)), np.resize(self._y, 2 * len(self._y))
            self._x[:n], self._y[:n] = self.x, self.y
            self._start, self._end = 0, n
        self._x[self._end], self._y[self._end] = node_us, hub_ns
        self._end += 1

    def drop_before(self, hub_ns: int) -> None:
        self._start += int(np.searchsorted(self.y, hub_ns))

    def clear(self) -> None:
        self._start = self._end = 0

    def last(self) -> tuple[float, int]:
        return float(self._x[self._end - 1]), int(self._y[self._end - 1])

    @property
    def x(self) -> np.ndarray:
        return self._x[self._start:self._end]

    @property
    def y(self) -> np.ndarray:
        return self._y[self._start:self._end]


class NodeClock:
    """One node's clock fit (see the module docstring)."""

    def __init__(self, window_s: float = 10.0, nominal_rate: float = 1000.0):
        self.window_ns = int(window_s * 1e9)
        self.nominal_rate = nominal_rate  # hub ns per node us
        self.pairs = _Pairs()  # (node us unwrapped, hub ns)
        self.line: tuple[float, float] | None = None  # hub_ns = a + b * node_us, relative to origin
        self.origin: tuple[float, int] = (0.0, 0)  # (node us, hub ns) the line is written about
        self.last_mapped_ns: int | None = None
        self.stats = ClockStats()
        self._new = 0  # pairs since the last fit
        self._below_ns = np.zeros(0)

    @property
    def fitted(self) -> bool:
        return self.line is not None and len(self.pairs) >= 2

    def add_pair(self, hub_tx_ns: int, node_rx_us32: int) -> None:
        """A Sync sent at hub_tx_ns (hub clock) and received at node_rx_us32 (the node's timer,
        32 bits)."""
        node_us = self._unwrap(node_rx_us32, hub_tx_ns)
        if node_us is None:  # the node restarted
            self.pairs.clear()
            self.line, self.last_mapped_ns = None, None
            self.stats.restarts += 1
            node_us = float(node_rx_us32)
        self.pairs.append(node_us, hub_tx_ns)
        self.pairs.drop_before(hub_tx_ns - self.window_ns)
        self._new += 1
        if len(self.pairs) <= REFIT_EVERY_PAIR or self._new >= REFIT_FRACTION * len(self.pairs):
            self._fit()

    def to_hub_ns(self, node_us: float) -> int | None:
        """The hub time of an (unwrapped) node time; None before the first pair."""
        if self.line is None:
            return None
        a, b = self.line
        return self.origin[1] + int(round(a + b * (node_us - self.origin[0])))

    def to_node_us(self, hub_ns: int) -> float | None:
        """The node time (unwrapped) at a hub time; None before the first pair."""
        if self.line is None:
            return None
        a, b = self.line
        return self.origin[0] + (hub_ns - self.origin[1] - a) / b

    def map_sample(self, node_us: float) -> int | None:
        """to_hub_ns of a sample's node time, never before the previous sample's."""
        t = self.to_hub_ns(node_us)
        if t is None:
            return None
        if self.last_mapped_ns is not None and t <= self.last_mapped_ns:
            t = self.last_mapped_ns + 1
            self.stats.held += 1
        self.last_mapped_ns = t
        return t

    def _unwrap(self, node_us32: int, hub_ns: int) -> float | None:
        """The 32-bit time unwrapped near the fit's (or the last pair's) prediction; None when
        it is far from every candidate (a restart)."""
        if not self.pairs:
            return float(node_us32)
        if self.line is not None:
            predicted = self.to_node_us(hub_ns)
        else:
            last_us, last_ns = self.pairs.last()
            predicted = last_us + (hub_ns - last_ns) / self.nominal_rate
        node_us = node_us32 + round((predicted - node_us32) / WRAP_US) * WRAP_US
        return float(node_us) if abs(node_us - predicted) <= REBOOT_JUMP_US else None

    def _fit(self) -> None:
        x0, y0 = self.pairs.last()
        x, y = self.pairs.x - x0, (self.pairs.y - y0).astype(float)
        span = float(x.max() - x.min())
        if span > 0:
            # the slope moves by far less than 20 ppm between fits: 20 ppm over the span bounds
            # how far below the top a touching pair can lie
            margin = max(PRUNE_MARGIN_NS, 0.02 * span) if self.line is not None and len(self.pairs) > 20 else np.inf
            a, b = upper_envelope_line(x, y, None if self.line is None else self.line[1], margin)
        else:  # one pair (or pairs at one node time): through the latest, at the rate known so far
            a, b = 0.0, self.nominal_rate if self.line is None else self.line[1]
        self.origin, self.line, self._new = (x0, y0), (a, b), 0
        self.stats.pairs = len(self.pairs)
        self._below_ns = (a + b * x) - y

    @property
    def residual_us(self) -> float:
        """Median distance of the window's pairs below the line (µs): their queuing delays."""
        return float(np.median(self._below_ns) / 1e3) if len(self._below_ns) else float("nan")
