"""The boxes' side of systemd's service notifications (sd_notify(3)): READY=1 when a box's work
loop first turns (a camera box's first frame, the hub's first cycle), then WATCHDOG=1 from that
loop at half the watchdog period, so that systemd restarts a box that hangs (WatchdogSec= in
edge/systemd's units) as it restarts one that ends. Outside systemd (no NOTIFY_SOCKET) it does
nothing. A notification that cannot be sent is counted and logged once: a box never stops
because its supervisor is gone."""

from __future__ import annotations

import logging
import os
import socket
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from typing import TypeVar

log = logging.getLogger(__name__)
T = TypeVar("T")


class Supervisor:
    def __init__(self, environ: Mapping[str, str] = os.environ, clock: Callable[[], float] = time.monotonic):
        """environ: NOTIFY_SOCKET (a path, or @name for the abstract namespace) and WATCHDOG_USEC
        (with WATCHDOG_PID, when set, naming this process), as systemd sets them."""
        path = environ.get("NOTIFY_SOCKET", "")
        self.address = "\0" + path[1:] if path.startswith("@") else path
        usec, pid = environ.get("WATCHDOG_USEC", ""), environ.get("WATCHDOG_PID", "")
        mine = not pid or pid == str(os.getpid())
        self.interval_s = int(usec) / 2e6 if usec.isdigit() and int(usec) > 0 and mine else None
        self.clock, self.failed, self._ready, self._last = clock, 0, False, -float("inf")
        self._socket = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) if self.address else None
        if self._socket is not None:  # a supervisor that does not read (its queue full) never blocks the box
            self._socket.setblocking(False)

    def turn(self) -> None:
        """One turn of the box's work loop: READY=1 the first time, WATCHDOG=1 when due."""
        if self._socket is None:
            return
        if not self._ready:
            self._ready = True
            self._send("READY=1")
        now = self.clock()
        if self.interval_s is not None and now - self._last >= self.interval_s:
            self._last = now
            self._send("WATCHDOG=1")

    def each(self, items: Iterable[T]) -> Iterator[T]:
        """items, with a turn for each."""
        for item in items:
            self.turn()
            yield item

    def close(self) -> None:
        if self._socket is not None:
            self._send("STOPPING=1")
            self._socket.close()
            self._socket = None

    def _send(self, state: str) -> None:
        try:
            self._socket.sendto(state.encode(), self.address)
        except OSError as e:
            self.failed += 1
            if self.failed == 1:
                log.warning("systemd notification %s not sent to %r (%s); the box carries on", state,
                            self.address, e)
