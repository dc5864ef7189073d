"""Simulated nodes served as a CAN bus over TCP in socketcand's protocol — the daemon that
exposes a Linux box's SocketCAN interface on the network, and that python-can's `socketcand`
interface connects to. The simulated studio's hub is a separate process reading a real
python-can bus, as on a box; a python-can `virtual` bus lives in one process, and there the
nodes' simulation and the hub's decoding share one interpreter lock.

One client at a time, in raw mode (socketcand's text protocol, ASCII, one message per <...>):
    server: < hi >          client: < open CHANNEL >   server: < ok >
    client: < rawmode >     server: < ok >
    then the server sends < frame ID SECONDS.MICROS DATAHEX > for every frame on the bus
    (stamped when it was handed to the client, on the server's clock: here the hub's own)
    and the client sends < send ID LENGTH B0 B1 ... > (bytes in hex).
Nothing is sent after the handshake until the client's first frame: python-can reads each
handshake reply with one recv, and a frame sent right behind it would share that read.
A client that goes away is waited for again; the nodes run on (after their stream ends too:
heartbeats and Sync answers, as nodes left powered on) until stop().
"""

from __future__ import annotations

import contextlib
import dataclasses
import select
import socket
import time
from typing import Protocol

MAX_MESSAGE = 200  # bytes: the longest < send ... > a classic frame makes is ~40


class Nodes(Protocol):
    def on_frame(self, frame_id: int, data: bytes, now_ns: int) -> list[tuple[int, bytes]]: ...
    def due(self, now_ns: int) -> list[tuple[int, bytes]]: ...
    def next_due_ns(self) -> int: ...


@dataclasses.dataclass
class ServerCounts:
    clients: int = 0
    frames_sent: int = 0
    frames_received: int = 0
    malformed: int = 0  # client messages that were not a handshake step or a valid < send >


def frame_message(frame_id: int, data: bytes, now_ns: int) -> bytes:
    return f"< frame {frame_id:03X} {now_ns // 1_000_000_000}.{now_ns // 1000 % 1_000_000:06d} {data.hex().upper()} >"\
        .encode()


def parse_send(message: str) -> tuple[int, bytes] | None:
    """(frame id, data) of a `< send ID LENGTH B0 ... >` message, None if it is not a valid one."""
    parts = message[1:-1].split()
    if len(parts) < 3 or parts[0] != "send":
        return None
    try:
        frame_id, length, data = int(parts[1], 16), int(parts[2], 16), bytes(int(b, 16) for b in parts[3:])
    except ValueError:
        return None
    return (frame_id, data) if length == len(data) <= 8 and frame_id < 0x800 else None


class Server:
    def __init__(self, nodes: Nodes, listener: socket.socket, clock_ns=time.time_ns):
        self.nodes, self.listener, self.clock_ns = nodes, listener, clock_ns
        self.counts = ServerCounts()

    def run(self, stop=lambda: False) -> ServerCounts:
        """Serves one client after another until stop()."""
        while not stop():
            client = self._accept(stop)
            if client is None:
                break
            with client, contextlib.suppress(OSError):  # a client gone mid-handshake: the next one
                self._serve(client, stop)
        return self.counts

    def _accept(self, stop) -> socket.socket | None:
        self.listener.settimeout(0.2)
        while not stop():
            try:
                client, _ = self.listener.accept()
            except TimeoutError:
                self._due()  # the nodes run on, unheard
                continue
            client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self.counts.clients += 1
            return client
        return None

    def _serve(self, client: socket.socket, stop) -> None:
        """One client until it leaves or stop()."""
        client.sendall(b"< hi >")
        buffer, open_bus, raw, heard = "", False, False, False
        while not stop():
            wait_s = max(0.0, min(0.05, (self.nodes.next_due_ns() - self.clock_ns()) * 1e-9))
            readable, _, _ = select.select([client], [], [], wait_s)
            if readable:
                try:
                    chunk = client.recv(65536).decode("ascii", "replace")
                except OSError:
                    chunk = ""
                if not chunk:
                    return  # the client went away: wait for the next
                buffer += chunk
                messages, buffer = _split(buffer)
                self.counts.malformed += len(buffer) > MAX_MESSAGE
                buffer = "" if len(buffer) > MAX_MESSAGE else buffer
                out = []
                for message in messages:
                    if message == "< rawmode >" and open_bus:
                        raw = True
                        client.sendall(b"< ok >")
                    elif message.startswith("< open ") and not open_bus:
                        open_bus = True
                        client.sendall(b"< ok >")
                    elif raw:
                        out += self._from_client(message)
                        heard = True
                    else:
                        self.counts.malformed += 1
                self._send(client, out)
            due = self._due()
            self._send(client, due if heard else [])  # before the client's first frame: unheard

    def _from_client(self, message: str) -> list[bytes]:
        frame = parse_send(message)
        if frame is None:
            self.counts.malformed += 1
            return []
        self.counts.frames_received += 1
        now = self.clock_ns()
        return [frame_message(i, d, now) for i, d in self.nodes.on_frame(*frame, now)]

    def _due(self) -> list[bytes]:
        now = self.clock_ns()
        return [frame_message(i, d, now) for i, d in self.nodes.due(now)]

    def _send(self, client: socket.socket, messages: list[bytes]) -> None:
        if messages:
            try:
                client.sendall(b"".join(messages))
            except OSError:
                return  # the client went away: the next read says so
            self.counts.frames_sent += len(messages)


def _split(buffer: str) -> tuple[list[str], str]:
    """The complete `< ... >` messages in buffer, and what is left after them."""
    messages = []
    while True:
        start = buffer.find("<")
        end = buffer.find(">", start)
        if start < 0 or end < 0:
            return messages, buffer[start:] if start >= 0 else ""
        messages.append(buffer[start:end + 1])
        buffer = buffer[end + 1:]


def listen(port: int, host: str = "127.0.0.1") -> socket.socket:
    return socket.create_server((host, port))
