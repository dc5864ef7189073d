"""The monitor's server: one asyncio loop subscribing to mocapd's output (ZeroMQ) and serving the
page (HTTP) and its WebSocket (/ws) on one port. Each browser gets the scene once, then every
Health and each performer's newest pose: a browser that falls behind skips poses (the page sees
the gap in the frame index) and never delays the subscriber or another browser."""

from __future__ import annotations

import asyncio
import json
import logging
import mimetypes
from collections.abc import Callable
from pathlib import Path
from typing import Any

import zmq
import zmq.asyncio
from websockets.asyncio.server import ServerConnection, serve
from websockets.datastructures import Headers
from websockets.exceptions import ConnectionClosed
from websockets.http11 import Request, Response

from mocap.monitor import messages
from mocap.net import transport, wire
from mocap.net.keys import ClientKeys

HTTP_LOG = logging.getLogger("mocap.monitor.http")  # websockets logs each page file at INFO: warnings only
HTTP_LOG.setLevel(logging.WARNING)

WEB = Path(__file__).parent / "web"
THREE = WEB / "node_modules" / "three"  # `npm ci` there, by `make setup`
PAGES = {"/": WEB / "index.html", "/monitor.js": WEB / "monitor.js", "/view.js": WEB / "view.js",
         "/style.css": WEB / "style.css"}
VENDOR = "/vendor/three/"  # three.js's build/ and examples/jsm/ as npm installed them
SOCKET_PATH = "/ws"


def static_file(path: str) -> Path | None:
    """The file the page asks for at `path`, or None: the page's own files, and three.js's
    modules under VENDOR (nothing outside its folder)."""
    if path in PAGES:
        return PAGES[path]
    if not path.startswith(VENDOR):
        return None
    root = THREE.resolve()
    file = (root / path.removeprefix(VENDOR)).resolve()
    return file if file.is_file() and file.is_relative_to(root) and file.suffix == ".js" else None


def _response(status: int, reason: str, body: bytes, content_type: str) -> Response:
    headers = Headers([("Content-Type", content_type), ("Content-Length", str(len(body))),
                       ("Cache-Control", "no-cache"), ("Connection", "close")])
    return Response(status, reason, headers, body)


def serve_static(connection: ServerConnection, request: Request) -> Response | None:
    """process_request: a page file, or None to go on with the WebSocket handshake on /ws."""
    path = request.path.split("?", 1)[0]
    if path == SOCKET_PATH:
        return None
    file = static_file(path)
    if file is None:
        hint = " (three.js missing: run `make setup`)" if path.startswith(VENDOR) and not THREE.is_dir() else ""
        return _response(404, "Not Found", f"not found: {path}{hint}\n".encode(), "text/plain; charset=utf-8")
    content_type = mimetypes.guess_type(file.name)[0] or "application/octet-stream"
    if content_type in ("text/javascript", "application/javascript"):
        content_type = "text/javascript; charset=utf-8"
    return _response(200, "OK", file.read_bytes(), content_type)


class Browser:
    """One connected page: the newest message of each kind (a pose: of each performer) waits
    for its turn to be sent."""

    def __init__(self, connection: ServerConnection) -> None:
        self.connection = connection
        self.pending: dict[str, str] = {}
        self.wake = asyncio.Event()

    def offer(self, kind: str, text: str) -> None:
        self.pending[kind] = text  # replaces an unsent one of its kind
        self.wake.set()

    async def pump(self) -> None:
        while True:
            await self.wake.wait()
            self.wake.clear()
            while self.pending:
                kind = next(iter(self.pending))
                await self.connection.send(self.pending.pop(kind))


class Monitor:
    """Subscribes to `connect` (mocapd's output endpoints) and serves the page; `scene` is the
    page's first message (mocap.monitor.scene)."""

    def __init__(self, connect: list[str], scene: dict[str, Any], keys: ClientKeys | None = None) -> None:
        self.connect, self.keys = connect, keys
        self.scene_text = json.dumps(scene)
        self.browsers: set[Browser] = set()
        self.received = {"pose": 0, "health": 0, "dropped": 0}

    def publish(self, kind: str, message: dict[str, Any]) -> None:
        text = json.dumps(message)
        for browser in self.browsers:
            browser.offer(kind, text)

    async def subscribe(self) -> None:
        """mocapd's messages to every browser; an undecodable one is counted and dropped."""
        socket = transport.subscriber(zmq.asyncio.Context.instance(), self.connect, keys=self.keys)
        try:
            while True:
                frames = await socket.recv_multipart()
                try:
                    message = wire.decode(frames)
                except wire.WireError:
                    self.received["dropped"] += 1
                    continue
                self.deliver(message)
        finally:
            socket.close()

    def deliver(self, message: object) -> None:
        """A PoseFrame (the newest of each performer kept for each browser) or a Health to
        every browser; other messages are not shown."""
        if isinstance(message, wire.PoseFrame):
            self.received["pose"] += 1
            self.publish(f"pose/{message.subject_id}", messages.pose(message))
        elif isinstance(message, wire.Health):
            self.received["health"] += 1
            self.publish("health", messages.health(message))

    async def page_socket(self, connection: ServerConnection) -> None:
        """One browser's WebSocket: the scene, then what subscribe() offers, until it closes."""
        browser = Browser(connection)
        browser.offer("scene", self.scene_text)
        self.browsers.add(browser)
        pump = asyncio.create_task(browser.pump())
        try:
            await connection.wait_closed()
        finally:
            self.browsers.discard(browser)
            pump.cancel()
            try:
                await pump
            except (asyncio.CancelledError, ConnectionClosed):
                pass

    async def run(self, host: str, port: int, ready: Callable[[str], None] | None = None,
                  duration: float | None = None) -> None:
        """Serves until cancelled (or for `duration` s); ready(url) once the port listens."""
        async with serve(self.page_socket, host, port, process_request=serve_static, compression=None,
                         max_size=2**16, server_header=None, logger=HTTP_LOG) as server:
            bound = server.sockets[0].getsockname()
            if ready:
                ready(f"http://{_url_host(host)}:{bound[1]}/")
            subscriber = asyncio.create_task(self.subscribe())
            try:
                await asyncio.wait_for(asyncio.shield(subscriber), duration) if duration else await subscriber
            except TimeoutError:
                pass
            finally:
                subscriber.cancel()


def _url_host(host: str) -> str:
    return "127.0.0.1" if host in ("", "0.0.0.0") else f"[{host}]" if ":" in host else host
