"""A simulated sensor node's clock and the Sync exchange with the hub, for the clock fit's tests
and benchmark: the node's timer runs off by a constant rate error (±100 ppm) plus a slow random
walk of that rate, Syncs are delayed by queuing (uniform 0-0.5 ms) and some are lost."""

from __future__ import annotations

import numpy as np

from mocap_edge.hub.clock_fit import WRAP_US, NodeClock


class NodeOscillator:
    """node_us(true hub ns): the node's timer, started at start_us when the hub's clock read origin_ns,
    its rate error `ppm` wandering as a random walk. A pure function of time (the walk is drawn
    on a 10 ms grid as far as it is asked for), so the order of the queries does not matter
    within the last KEEP_S of the latest one asked (older grid points are let go: the live
    simulated nodes of a 10-minute soak otherwise held 64 MB of them)."""

    STEP_NS = 10_000_000
    KEEP_S = 60.0

    def __init__(self, ppm: float, start_us: float, walk_ppm_per_sqrt_s: float, rng: np.random.Generator,
                 origin_ns: int = 0):
        self.rng, self.walk, self.origin_ns = rng, walk_ppm_per_sqrt_s, origin_ns
        self._ppm = [ppm]
        self._node_us = [start_us]  # at grid points (self._first + j) * STEP_NS
        self._first = 0
        self._keep = round(self.KEEP_S * 1e9 / self.STEP_NS)

    def advance(self, t_ns: int) -> float:
        """The node's timer (unwrapped, µs) at hub time t_ns >= origin_ns; ValueError for a time
        more than KEEP_S before the latest one asked."""
        t_ns -= self.origin_ns
        k = int(t_ns // self.STEP_NS)
        if k < self._first:
            raise ValueError(f"node time asked {(self._first - k) * self.STEP_NS * 1e-9:.2f} s before the kept window")
        while len(self._node_us) <= k - self._first + 1:
            step_s = self.STEP_NS * 1e-9
            self._node_us.append(self._node_us[-1] + step_s * 1e6 * (1 + self._ppm[-1] * 1e-6))
            self._ppm.append(self._ppm[-1] + self.walk * np.sqrt(step_s) * self.rng.normal())
        if len(self._node_us) > 2 * self._keep:  # let go of all but the last KEEP_S
            drop = len(self._node_us) - self._keep
            del self._node_us[:drop], self._ppm[:drop]
            self._first += drop
        j = k - self._first
        frac = (t_ns - k * self.STEP_NS) / self.STEP_NS
        return self._node_us[j] + frac * (self._node_us[j + 1] - self._node_us[j])


def sample_errors_us(seconds: float = 10.0, sync_hz: float = 10.0, sample_hz: float = 60.0,
                     delay_max_us: float = 500.0, lost: float = 0.01, seed: int = 0,
                     window_s: float = 10.0) -> tuple[np.ndarray, np.ndarray]:
    """(sample times s, |mapped - true| µs) of one simulated node's samples, each mapped with
    the fit of the Syncs before it (the hub maps a sample when it arrives)."""
    rng = np.random.default_rng(seed)
    osc = NodeOscillator(rng.uniform(-100, 100), rng.uniform(0, WRAP_US), 0.1, rng)
    clock = NodeClock(window_s)
    events = sorted([(int(t * 1e9), 0) for t in np.arange(0, seconds, 1 / sync_hz)]
                    + [(int(t * 1e9), 1) for t in np.arange(0.5 / sample_hz, seconds, 1 / sample_hz)])
    times, errors = [], []
    for t_ns, kind in events:
        if kind == 0:
            arrival = t_ns + int(rng.uniform(0, delay_max_us) * 1e3)
            node = osc.advance(arrival)
            if rng.random() >= lost:
                clock.add_pair(t_ns, int(node) % WRAP_US)
        elif clock.fitted:
            node = osc.advance(t_ns)
            mapped = clock.to_hub_ns(np.floor(node))
            times.append(t_ns * 1e-9)
            errors.append(abs(mapped - t_ns) / 1e3)
    return np.array(times), np.array(errors)
