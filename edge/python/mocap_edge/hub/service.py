"""The hub running: Syncs sent on the bus at sync_hz, every received frame fed to the hub's core
(mocap_edge.hub.hub) with its receive timestamp, each node configured when it is discovered
(stop, rate, ranges, mode, start, as hub.toml says), the IMUs on the hub's own I2C bus polled,
and an ImuBatch published as soon as every sampling node's sample of a round is in (nodes on
CAN only), at the latest every batch period. Bus errors (an error frame, a send refused:
bus-off, a full queue) are counted (bus_errors) and the loop goes on: python-can raises them,
the kernel (SocketCAN's restart-ms) or the adapter recovers the bus.
"""

from __future__ import annotations

import contextlib
import logging
import time

import can
import zmq
from mocap.net import transport, wire
from mocap.net.keys import ServerKeys

from mocap_edge.errors import EdgeError
from mocap_edge.hub.bus_errors import BusErrors
from mocap_edge.hub.can_bus import CanPort
from mocap_edge.hub.can_db import NODE_ID_MASK
from mocap_edge.hub.hub import Hub

log = logging.getLogger(__name__)
SYNC_ID = 0x080
HUB_IDS = (SYNC_ID, 0x600)  # the frame ids (less the node id) of the hub's messages: Sync, Command
DRAIN = 64  # frames fed before the timers are looked at again
RETRY_S = 0.1  # after the adapter failed
REOPEN_NS = 1_000_000_000  # between attempts to open a link that went away
EMPTY_READS = 50  # reads in a row that return at once with nothing: the peer is gone (a closed socket
# spins through thousands a second; a read that ends inside a message returns nothing once)
HEALTH_NS = 1_000_000_000  # a Health report every second


class HubService:
    def __init__(self, port: CanPort | None, hub: Hub, publish, clock_ns=time.time_ns, local: list | None = None,
                 reopen=None):
        """publish(message) sends an ImuBatch or the hub's Health; clock_ns is the hub's clock
        (the shared timebase). port None: no CAN bus; local: the IMUs on the hub's own I2C bus
        (mocap_edge.hub.i2c.I2cImu, timed on clock_ns), polled every batch period. reopen():
        a new CanPort (EdgeError when it cannot be opened yet), for a link that went away (a
        socketcand server or an SLCAN adapter's TCP port closed): tried once a second."""
        self.port, self.hub, self.publish, self.clock_ns = port, hub, publish, clock_ns
        self.reopen, self._reopen_at, self._empty_reads = reopen, 0, 0
        self.local = local or []
        self._local_reported: dict[str, tuple[int, int | None]] = {}
        self.bus_errors = BusErrors()
        self.configured: dict[int, int] = {}  # node id -> its reboots when it was configured
        self._sync_seq = 0
        self._refused = 0  # sends refused in a row (logged when it starts and when it ends)

    def run(self, stop, duration_s: float = 0.0) -> int:
        """Runs until stop() is true (or duration_s passed, if > 0); returns batches published.
        A timer that fell behind (the hub was descheduled) restarts a period from now: no
        burst of Syncs or empty batches to catch up."""
        c = self.hub.config
        sync_ns, batch_ns = int(1e9 / c.sync_hz), int(c.batch_ms * 1e6)
        start = now = self.clock_ns()
        next_sync, next_batch, next_health, published = now, now + batch_ns, now + HEALTH_NS, 0
        while not stop() and not (duration_s > 0 and now - start >= duration_s * 1e9):
            if self.port is None and self.reopen is not None and now >= self._reopen_at:
                self._try_reopen(now)
            if now >= next_sync and self.port is not None:
                self._send_sync()
                next_sync = _after(next_sync, sync_ns, now)
            self._wait(max(0.0, min(next_sync if self.port else next_batch, next_batch) - self.clock_ns()) * 1e-9)
            now = self.clock_ns()
            if now >= next_batch or (not self.local and self.hub.round_complete(now)):
                for imu in self.local:
                    self.hub.add_samples(imu.poll(now))
                batch = self.hub.take_batch(now)
                if batch is not None:
                    self.publish(batch)
                    published += 1
                if now >= next_batch:
                    next_batch = _after(next_batch, batch_ns, now)
                    self._configure_new_nodes()
            if now >= next_health:
                health = self.hub.health(now, self.bus_errors)
                self._local_health(health, now)
                self.publish(health)
                next_health = _after(next_health, HEALTH_NS, now)
        return published

    def _wait(self, timeout_s: float) -> None:
        """Feeds the CAN frames that arrive within timeout_s; sleeps it with no CAN bus."""
        if self.port is not None:
            self._drain(timeout_s)
        else:
            time.sleep(timeout_s)

    def _local_health(self, health, now_ns: int) -> None:
        """One stream per IMU on the hub's I2C bus, as for a node: active while it delivers,
        its rate since the previous report, samples, losses (FIFO overflows), invalid packets
        as malformed, failed transfers (NACKs) as bus errors."""
        for imu in self.local:
            c = imu.counts
            before, at = self._local_reported.get(imu.name, (0, None))
            rate = (c.published - before) / ((now_ns - at) * 1e-9) if at is not None and now_ns > at else 0.0
            self._local_reported[imu.name] = (c.published, now_ns)
            health.streams.add(stream=f"imu/{imu.name}", active=imu.running and c.published > before,
                               rate_hz=rate, received=c.published, lost=c.lost, malformed=c.invalid,
                               dropped=c.invalid, bus_errors=c.nacks)

    def _drain(self, timeout_s: float) -> None:
        """Feeds what is waiting (up to DRAIN frames, waiting at most timeout_s for the first).
        An adapter that fails (unplugged, its socket closed) is counted, and tried again after
        a pause: the hub keeps running."""
        try:
            asked = time.monotonic()
            message = self.port.bus.recv(timeout=timeout_s)
            if message is None and timeout_s >= 0.005 and time.monotonic() - asked < timeout_s / 10:
                self._empty_reads += 1  # python-can's socketcand reads a closed socket as "nothing yet"
                if self._empty_reads >= EMPTY_READS:
                    self._lose_link()
                return
            self._empty_reads = 0
            for _ in range(DRAIN):
                if message is None:
                    return
                self._receive(message)
                message = self.port.bus.recv(timeout=0.0)
            if message is not None:
                self._receive(message)
        except can.CanOperationError:
            self.bus_errors.receive_failed()
            time.sleep(RETRY_S)

    def _send(self, frame_id: int, data: bytes) -> bool:
        if self.port is None:  # no bus, or its link went away (a send before may have found that)
            return False
        try:
            self.port.bus.send(can.Message(arbitration_id=frame_id, data=data, is_extended_id=False), timeout=0.01)
        except (can.CanOperationError, OSError) as e:  # socketcand's socket raises OSError
            self.bus_errors.send_refused(e)
            if not self._refused:
                log.warning("%s: send refused (%s): counted, the hub goes on", self.port.name, e)
            self._refused += 1
            if isinstance(e, ConnectionError):  # the link's peer is gone (a TCP link)
                self._lose_link()
            return False
        self.bus_errors.send_succeeded()
        if self._refused:
            log.warning("%s: sending again after %d refused sends", self.port.name, self._refused)
            self._refused = 0
        return True

    def _lose_link(self) -> None:
        """The adapter's link is gone: closed, counted, and opened again later (reopen)."""
        self.bus_errors.counts["link_lost"] += 1
        with contextlib.suppress(Exception):  # already broken: closing it may fail too
            self.port.bus.shutdown()
        self.port, self._empty_reads = None, 0
        self._reopen_at = self.clock_ns() + REOPEN_NS

    def _try_reopen(self, now_ns: int) -> None:
        try:
            self.port = self.reopen()
        except EdgeError:
            self._reopen_at = now_ns + REOPEN_NS

    def _send_sync(self) -> None:
        seq = self._sync_seq
        self._sync_seq = (self._sync_seq + 1) % 256
        # Without an echo, the time just before the send: the frame cannot leave earlier, so
        # every pair stays on or below the node's line (a stamp taken after the send returned
        # is late by however long the hub was descheduled, and such a pair lifts the envelope).
        before_ns = self.clock_ns()
        if self._send(*self.hub.db.sync(seq)) and not self.port.echoes:
            self.hub.sync_sent(seq, before_ns)  # else its transmit time comes with its echo

    def _receive(self, message: can.Message) -> None:
        if message.is_error_frame:
            self.bus_errors.error_frame(message)
            return
        stamp = int(round(message.timestamp * 1e9)) if message.timestamp else self.clock_ns()
        if not message.is_rx and (message.arbitration_id & ~NODE_ID_MASK) in HUB_IDS:
            # our own frame, echoed: a Sync's echo is its transmit time. python-can marks every
            # frame sent from this machine as not received (SocketCAN's MSG_DONTROUTE), another
            # process's too (vcan, can-utils): only the kinds the hub sends are taken as its own.
            if message.arbitration_id == SYNC_ID and len(message.data) == 1:
                self.hub.sync_sent(message.data[0], stamp)
            return
        self.hub.on_frame(stamp, message.arbitration_id, bytes(message.data), message.is_extended_id,
                          message.is_remote_frame)

    def _configure_new_nodes(self) -> None:
        """Each named node heard for the first time (or after a reboot) gets the hub's
        configuration: stop, rate, ranges, mode, start."""
        c = self.hub.config
        for node in self.hub.nodes.values():
            if not node.name or node.heartbeat is None:
                continue
            if self.configured.get(node.id) == node.counts.reboots:
                continue
            for command, args in (("stop", {}), ("set_rate", {"rate_hz": c.rate_hz}),
                                  ("set_ranges", {"acc_range_g": c.acc_range_g, "gyro_range_dps": c.gyro_range_dps}),
                                  ("set_mode", {"mode": 1 if c.mode == "9d" else 0}), ("start", {})):
                self._send(*self.hub.db.command(node.id, command, **args))
            self.configured[node.id] = node.counts.reboots


def _after(due_ns: int, period_ns: int, now_ns: int) -> int:
    """The timer's next time: a period on, or a period from now when it fell behind."""
    return due_ns + period_ns if due_ns + period_ns > now_ns else now_ns + period_ns


def publisher(endpoint: str, keys: ServerKeys | None = None):
    """A publish(message) function on a ZeroMQ PUB socket bound at endpoint (a CURVE server
    with keys), and the socket."""
    socket = transport.publisher(zmq.Context.instance(), endpoint, keys=keys)
    return lambda batch: socket.send_multipart(wire.encode(batch)), socket
