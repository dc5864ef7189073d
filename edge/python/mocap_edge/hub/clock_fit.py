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
line) is held at that one plus a nanosecond, and counted.
"""

from __future__ import annotations

import collections
import dataclasses

import numpy as np

WRAP_US = 1 << 32  # the node's timer
REBOOT_JUMP_US = 5_000.0  # a reported time this far from the fit's prediction: the node restarted


@dataclasses.dataclass
class ClockStats:
    pairs: int = 0  # Sync pairs used since the last restart
    restarts: int = 0  # fits started again (the node's timer jumped: a reboot)
    held: int = 0  # mapped times held so as not to go backwards
    residual_us: float = float("nan")  # median distance of the window's pairs below the line


def upper_envelope_line(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """(a, b) of y = a + b·x, the line on or above every point that minimises the summed
    distance to them: the upper hull's edge at mean(x). At least two distinct x."""
    order = np.lexsort((y, x))
    x, y = x[order], y[order]
    hull: list[int] = []
    for i in range(len(x)):  # monotone chain, upper hull, left to right
        while len(hull) >= 2:
            o, a = hull[-2], hull[-1]
            if (x[a] - x[o]) * (y[i] - y[o]) - (y[a] - y[o]) * (x[i] - x[o]) >= 0:
                hull.pop()  # a lies on or below the chord o-i
            else:
                break
        if hull and x[hull[-1]] == x[i]:
            hull.pop()  # same x: keep the higher (later in the sort)
        hull.append(i)
    if len(hull) == 1:
        raise ValueError("the points have one x: no line")
    mean = x.mean()
    k = int(np.clip(np.searchsorted(x[hull], mean) - 1, 0, len(hull) - 2))
    i, j = hull[k], hull[k + 1]
    b = (y[j] - y[i]) / (x[j] - x[i])
    return float(y[i] - b * x[i]), float(b)


class NodeClock:
    """One node's clock fit (see the module docstring)."""

    def __init__(self, window_s: float = 10.0, nominal_rate: float = 1000.0):
        self.window_ns = int(window_s * 1e9)
        self.nominal_rate = nominal_rate  # hub ns per node us
        self.pairs: collections.deque[tuple[float, int]] = collections.deque()  # (node us unwrapped, hub ns)
        self.line: tuple[float, float] | None = None  # hub_ns = a + b * node_us, relative to origin
        self.origin: tuple[float, int] = (0.0, 0)  # (node us, hub ns) the line is written about
        self.last_mapped_ns: int | None = None
        self.stats = ClockStats()

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
        self.pairs.append((node_us, hub_tx_ns))
        while self.pairs and hub_tx_ns - self.pairs[0][1] > self.window_ns:
            self.pairs.popleft()
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
            last_us, last_ns = self.pairs[-1]
            predicted = last_us + (hub_ns - last_ns) / self.nominal_rate
        k = np.round((predicted - node_us32) / WRAP_US)
        node_us = node_us32 + k * WRAP_US
        return float(node_us) if abs(node_us - predicted) <= REBOOT_JUMP_US else None

    def _fit(self) -> None:
        x0, y0 = self.pairs[-1]
        x = np.array([p[0] - x0 for p in self.pairs])
        y = np.array([float(p[1] - y0) for p in self.pairs])
        if len(self.pairs) >= 2:
            a, b = upper_envelope_line(x, y)
        else:  # one pair: through it, at the rate known so far
            a, b = 0.0, self.nominal_rate if self.line is None else self.line[1]
        self.origin, self.line = (x0, y0), (a, b)
        self.stats.pairs = len(self.pairs)
        below = (a + b * x) - y
        self.stats.residual_us = float(np.median(below) / 1e3)
