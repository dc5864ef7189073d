"""What went wrong on the hub's CAN bus, counted: error frames (SocketCAN hands the controller's
error states over as frames whose id carries the error class, linux/can/error.h), sends the
adapter refused, reads that failed — and bus-off with its recoveries. A controller goes bus-off
after too many transmit errors (a short, a missing terminator, a node babbling) and stops
sending until it is restarted (SocketCAN's restart-ms, or the adapter itself): bus-off is
counted when an error frame says so or a send is refused as bus-off, a recovery when a restart
frame comes or a send succeeds after it.
"""

from __future__ import annotations

import collections

import can

CAN_ERR_BUSOFF = 0x040  # error class bits of a SocketCAN error frame's id
CAN_ERR_RESTARTED = 0x100


class BusErrors:
    def __init__(self):
        self.counts: collections.Counter[str] = collections.Counter()
        self.bus_off = False  # the controller is bus-off (as far as the hub can tell)

    def total(self) -> int:
        """Error frames, refused sends and failed reads (bus-off and recoveries are among them)."""
        return sum(v for k, v in self.counts.items() if k not in ("bus_off", "recoveries"))

    def error_frame(self, message: can.Message) -> None:
        self.counts["error_frames"] += 1
        if message.arbitration_id & CAN_ERR_BUSOFF:
            self._went_off()
        if message.arbitration_id & CAN_ERR_RESTARTED:
            self._recovered()

    def send_refused(self, error: Exception) -> None:
        self.counts["send_refused"] += 1
        if "off" in str(error).lower():  # python-can's messages for ENETDOWN / bus-off states
            self._went_off()

    def send_succeeded(self) -> None:
        self._recovered()

    def receive_failed(self) -> None:
        self.counts["receive_failed"] += 1

    def _went_off(self) -> None:
        if not self.bus_off:
            self.counts["bus_off"] += 1
        self.bus_off = True

    def _recovered(self) -> None:
        if self.bus_off:
            self.counts["recoveries"] += 1
        self.bus_off = False
