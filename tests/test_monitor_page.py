"""The live view end to end: the simulated studio's processes and mocapd live on loopback,
`mocap monitor` on mocapd's output, its page in headless Chromium. The page draws the poses
mocapd published (read back from the drawn joints, within 1 mm) and a camera box that stops
turns its stream, and its frustum, stale. Several performers (a publisher standing in for
mocapd): each drawn where its poses put it, one gone taken away."""

import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import zmq

from mocap import paths, processes
from mocap.demo import browser, play
from mocap.demo import studio as live_studio
from mocap.demo.live_studio import LiveStudio
from mocap.monitor import scene
from mocap.net import wire

pytestmark = [pytest.mark.skipif(not play.MOCAPD.exists(), reason="mocapd is not built (make build)"),
              pytest.mark.skipif(not browser.CHROMIUM.exists(), reason="Chromium is not installed (make setup)")]

STOPPED = "cam3"


def _monitor(*source: str) -> tuple[subprocess.Popen, str]:
    monitor = subprocess.Popen([sys.executable, "-m", "mocap.cli", "monitor", *source,
                                "--http", "127.0.0.1:0"], stdout=subprocess.PIPE, text=True,
                               preexec_fn=processes.die_with_parent())
    ready = monitor.stdout.readline().split()
    assert len(ready) == 3, f"mocap monitor did not start (status {monitor.poll()})"
    return monitor, ready[2]


def _published(live: LiveStudio, frame: int):
    """The PoseFrame `frame` as the test's own subscriber of mocapd received it."""
    def found(arrived):
        return next((a.message for a in arrived if getattr(a.message, "frame_index", -1) == frame), None)
    return live.wait(found, 5.0, f"PoseFrame {frame} at the test's own subscriber")


def test_the_page_draws_what_mocapd_published_and_shows_a_stopped_camera_stale(tmp_path):
    studio = live_studio.prepare(tmp_path, seconds=10.0, seed=3)
    with LiveStudio(studio) as live:
        monitor, url = _monitor("--session", str(studio.session))
        try:
            with browser.page(url) as page:
                page.wait_for_function("window.monitor && monitor.frames > 60 && monitor.health !== null",
                                       timeout=40_000)
                shown = page.evaluate("({frame: monitor.lastFrame.frame, drawn: monitor.drawnJoints(), "
                                      "webgl: monitor.webgl})")
                assert shown["webgl"], "the page could not draw (no WebGL)"
                pose = _published(live, shown["frame"])
                truth = {j.name: (j.px, j.py, j.pz) for j in pose.joints}
                assert set(shown["drawn"]["names"]) == set(truth)
                drawn = np.array(shown["drawn"]["joints"])
                expected = np.array([truth[n] for n in shown["drawn"]["names"]])
                assert np.abs(drawn - expected).max() < 1e-3  # metres
                assert page.evaluate(f"monitor.streams['camera/{STOPPED}'].state") == "ok"

                live.kill(STOPPED)
                page.wait_for_function(f"monitor.streams['camera/{STOPPED}'].state === 'stale'", timeout=10_000)
                row = page.locator(f'#streams tr[data-stream="camera/{STOPPED}"]')
                assert row.get_attribute("class") == "stale"
                others = page.evaluate("Object.values(monitor.streams).filter(s => s.name.startsWith('camera/'))"
                                       f".filter(s => s.name !== 'camera/{STOPPED}').map(s => s.state)")
                assert others and set(others) == {"ok"}, others
                page.wait_for_function(f"monitor.lastFrame.frame > {shown['frame'] + 60}", timeout=10_000)
        finally:
            monitor.terminate()
            monitor.wait(timeout=10)


def _person(subject: int, frame: int) -> wire.PoseFrame:
    """Performer `subject` standing 1 m beside the last, the same pose every frame."""
    pose = wire.PoseFrame(frame_index=frame, subject_id=subject, cameras=["cam1"], imus=[f"p{subject}_pelvis"] * subject)
    for b, bone in enumerate(scene.bones(paths.DEFAULT_SKELETON)):
        pose.joints.add(name=bone["name"], px=float(subject) + 0.01 * b, py=0.02 * b, pz=1.0 + 0.03 * b, qw=1.0)
    return pose


def _publish(socket: zmq.Socket, people: list[int], stop: threading.Event) -> None:
    frame = 0
    while not stop.is_set():
        for subject in tuple(people):  # the test takes one away meanwhile
            socket.send_multipart(wire.encode(_person(subject, frame)))
        frame += 1
        time.sleep(1 / 60)


def test_the_page_draws_every_performer_and_takes_away_one_no_longer_published():
    context = zmq.Context()
    publisher = context.socket(zmq.PUB)
    port = publisher.bind_to_random_port("tcp://127.0.0.1")
    people, stop = [1, 2, 3], threading.Event()
    sender = threading.Thread(target=_publish, args=(publisher, people, stop))
    sender.start()
    monitor, url = _monitor("--connect", f"tcp://127.0.0.1:{port}")
    try:
        with browser.page(url) as page:
            page.wait_for_function("window.monitor && monitor.people.length === 3", timeout=20_000)
            for subject in people:
                drawn = page.evaluate(f"monitor.drawnJoints({subject})")
                expected = {j.name: (j.px, j.py, j.pz) for j in _person(subject, 0).joints}
                assert np.abs(np.array(drawn["joints"]) - [expected[n] for n in drawn["names"]]).max() < 1e-3
            lines = page.locator("#people div")
            assert lines.count() == 3 and lines.nth(2).get_attribute("data-subject") == "3"
            assert "3 IMUs" in lines.nth(2).text_content()
            people.remove(2)  # the host no longer publishes person 2
            page.wait_for_function("monitor.people.join() === '1,3'", timeout=10_000)
            assert page.locator('#people div[data-subject="2"]').count() == 0
    finally:
        stop.set()
        sender.join()
        monitor.terminate()
        monitor.wait(timeout=10)
        publisher.close(0)
        context.term()
