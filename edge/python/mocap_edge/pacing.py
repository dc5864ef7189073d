"""Publishing at the times things happen: sleep until a deadline on the shared timebase."""

from __future__ import annotations

import time


def sleep_until(t_ns: int) -> None:
    while True:
        left = t_ns - time.time_ns()
        if left <= 0:
            return
        time.sleep(min(left, 50_000_000) * 1e-9)
