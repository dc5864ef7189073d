"""Converting a kernel clock's timestamps to CLOCK_REALTIME, the shared timebase (PTP-
disciplined through phc2sys in a studio, docs/sync.md).

The offset realtime - clock is measured, not assumed: it changes whenever the realtime
clock is stepped, so it is measured again for every frame (a few microseconds)."""

from __future__ import annotations

import time


def realtime_offset_ns(clock_id: int = time.CLOCK_MONOTONIC, samples: int = 3) -> int:
    """CLOCK_REALTIME - clock_id (ns), from the tightest of `samples` bracketed readings:
    the realtime reading is compared with the midpoint of the two clock readings around it,
    so the error is at most half the bracket (about a microsecond)."""
    best_span, best_offset = None, 0
    for _ in range(samples):
        before = time.clock_gettime_ns(clock_id)
        realtime = time.time_ns()
        after = time.clock_gettime_ns(clock_id)
        if best_span is None or after - before < best_span:
            best_span, best_offset = after - before, realtime - (before + after) // 2
    return best_offset
