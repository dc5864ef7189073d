"""The monitor's server without a browser: what it serves, what a page receives over its
WebSocket from a publisher standing in for mocapd (scene first, then every Health and the
newest pose; a page that falls behind skips poses, never the newest), and bad input on the
wire counted and dropped; bad command lines refused with a clear error."""

import asyncio
import json
import socket
import subprocess
import sys

import numpy as np
import zmq
import zmq.asyncio
from websockets.asyncio.client import connect

from mocap import _core, paths, rotations
from mocap.monitor import messages, scene, server
from mocap.net import wire

BONES = scene.bones(paths.DEFAULT_SKELETON)


def _pose(k: int, subject: int = 0) -> wire.PoseFrame:
    pose = wire.PoseFrame(capture_time_ns=1_700_000_000_000_000_000 + k * 16_666_667, frame_index=k,
                          cameras=["cam1", "cam2"], imus=["pelvis"], latency_ms=0.4, subject_id=subject)
    for b, bone in enumerate(BONES):
        pose.joints.add(name=bone["name"], px=0.1 * b + 0.01 * k, py=-0.05 * b, pz=1.0 + 0.001 * b, qw=1.0)
    return pose


def _health(active: bool) -> wire.Health:
    health = wire.Health(source="host", time_ns=1_700_000_000_000_000_000, latency_p50_ms=0.3, latency_p99_ms=0.8,
                         frames_solved=10)
    health.streams.add(stream="camera/cam1", active=active, rate_hz=60.0, received=600, late=2)
    health.streams.add(stream="imu/pelvis", active=True, distrusted=True, heading_correction_deg=3.5)
    return health


def test_the_page_and_three_js_are_served_and_nothing_else():
    assert server.static_file("/") == server.WEB / "index.html"
    assert server.THREE.is_dir(), "three.js is not installed: run `make setup` (npm ci in the monitor's web/)"
    module = server.static_file("/vendor/three/build/three.module.js")
    assert module is not None and module.read_text().startswith("/**")
    for escape in ("/vendor/three/../../index.html", "/vendor/three/../../../server.py", "/vendor/three/package.json",
                   "/etc/passwd", "/vendor/three/%2e%2e/x.js", "/../server.py"):
        assert server.static_file(escape) is None, escape


def test_health_says_which_streams_are_stale_or_distrusted():
    shown = {s["name"]: s for s in messages.health(_health(active=False))["streams"]}
    assert shown["camera/cam1"]["state"] == "stale" and shown["camera/cam1"]["late"] == 2
    assert shown["imu/pelvis"]["state"] == "distrusted" and shown["imu/pelvis"]["heading_correction_deg"] == 3.5
    assert messages.health(_health(active=True))["streams"][0]["state"] == "ok"


def test_health_of_several_people_carries_the_people_counts_and_of_one_none():
    health = _health(active=True)
    assert messages.health(health)["people"] is None
    health.people.tracked, health.people.born, health.people.suits_worn = 3, 4, 2
    people = messages.health(health)["people"]
    assert (people["tracked"], people["born"], people["retired"], people["suits_worn"]) == (3, 4, 0, 2)


def test_a_frustum_reaches_the_image_corners():
    camera = _core.Camera()
    camera.name, camera.width, camera.height = "cam1", 640, 480
    camera.fx = camera.fy = 500.0
    camera.cx, camera.cy = 320.0, 240.0
    camera.rotation = rotations.exp(np.array([0.3, -0.2, 1.0]))
    camera.translation = [0.5, -1.0, 4.0]
    shown = scene.frustum(camera)
    assert np.allclose(shown["centre"], camera.center(), atol=1e-4)
    pixels, valid = camera.project(np.array(shown["corners"]))
    assert valid.all() and np.allclose(pixels, [[0, 0], [640, 0], [640, 480], [0, 480]], atol=0.2)  # corners kept to 0.1 mm


async def _received(socket, kind: str, count: int = 1) -> list[dict]:
    out = []
    while len(out) < count:
        message = json.loads(await asyncio.wait_for(socket.recv(), 5.0))
        if message["type"] == kind:
            out.append(message)
    return out


async def _a_page_of_a_publisher() -> None:
    context = zmq.asyncio.Context()
    publisher = context.socket(zmq.PUB)
    port = publisher.bind_to_random_port("tcp://127.0.0.1")
    monitor = server.Monitor([f"tcp://127.0.0.1:{port}"], scene.scene(None))
    url = asyncio.get_running_loop().create_future()
    serving = asyncio.create_task(monitor.run("127.0.0.1", 0, url.set_result))
    try:
        async with connect((await url).replace("http", "ws") + "ws") as page:
            first = json.loads(await asyncio.wait_for(page.recv(), 5.0))
            assert first["type"] == "scene" and [b["name"] for b in first["bones"]] == [b["name"] for b in BONES]
            while monitor.received["pose"] == 0:  # until the subscription has reached the publisher
                await publisher.send_multipart(wire.encode(_pose(0)))
                await asyncio.sleep(0.02)
            await publisher.send_multipart([b"mocap.v1.PoseFrame", b"\xff\x00garbage"])
            await publisher.send_multipart(wire.encode(_health(active=False)))
            await publisher.send_multipart(wire.encode(_pose(7)))
            health = (await _received(page, "health"))[0]
            assert health["streams"][0]["state"] == "stale"
            poses = await _received(page, "pose", 1)
            while poses[-1]["frame"] != 7:
                poses += await _received(page, "pose")
            shown = np.array(poses[-1]["joints"])
            assert np.abs(shown - [[j.px, j.py, j.pz] for j in _pose(7).joints]).max() < 1e-4
            assert poses[-1]["names"] == [b["name"] for b in BONES] and monitor.received["dropped"] == 1
    finally:
        serving.cancel()
        publisher.close(0)
        context.term()


def test_a_page_gets_the_scene_then_health_and_poses_and_garbage_is_dropped():
    asyncio.run(_a_page_of_a_publisher())


class _SlowConnection:
    def __init__(self) -> None:
        self.sent, self.gate = [], asyncio.Event()

    async def send(self, text: str) -> None:
        await self.gate.wait()
        self.sent.append(json.loads(text))


async def _a_slow_page(people: int = 1) -> list[dict]:
    connection = _SlowConnection()
    browser = server.Browser(connection)
    pump = asyncio.create_task(browser.pump())
    browser.offer("scene", json.dumps({"type": "scene"}))
    await asyncio.sleep(0)  # the pump is waiting on the page with the scene
    monitor = server.Monitor([], {})
    monitor.browsers.add(browser)
    for k in range(100):
        for subject in range(people):
            monitor.deliver(_pose(k, subject))
    monitor.deliver(_health(True))
    connection.gate.set()
    for _ in range(100):  # what the page gets within 1 s
        await asyncio.sleep(0.01)
    pump.cancel()
    return connection.sent


def test_a_page_that_falls_behind_skips_poses_but_gets_the_newest_and_every_health():
    sent = asyncio.run(_a_slow_page())
    assert [m["type"] for m in sent] == ["scene", "pose", "health"]
    assert sent[1]["frame"] == 99


def test_a_page_that_falls_behind_gets_the_newest_pose_of_every_performer():
    sent = asyncio.run(_a_slow_page(people=3))
    assert [m["type"] for m in sent] == ["scene", "pose", "pose", "pose", "health"]
    assert [(m["subject"], m["frame"]) for m in sent[1:4]] == [(0, 99), (1, 99), (2, 99)]


def _monitor_cli(*args):
    return subprocess.run([sys.executable, "-m", "mocap.cli", "monitor", *args], capture_output=True, text=True,
                          timeout=60)


def test_a_bad_address_endpoint_or_a_taken_port_is_a_clear_error():
    out = _monitor_cli("--connect", "tcp://127.0.0.1:1", "--http", "127.0.0.1:http")
    assert out.returncode == 2 and "expected [HOST:]PORT with a port 0..65535" in out.stderr, out.stderr
    out = _monitor_cli("--http", "127.0.0.1:0")
    assert out.returncode == 2 and "--connect EP or --session FILE is needed" in out.stderr, out.stderr
    out = _monitor_cli("--connect", "foo", "--http", "127.0.0.1:0", "--duration", "5")
    assert out.returncode == 2 and "--connect foo: Invalid argument" in out.stderr, out.stderr
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        out = _monitor_cli("--connect", "tcp://127.0.0.1:1", "--http", f"127.0.0.1:{port}", "--duration", "5")
    assert out.returncode == 2 and f"--http 127.0.0.1:{port}:" in out.stderr and "in use" in out.stderr, out.stderr
