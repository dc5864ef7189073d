"""The live view end to end: the simulated studio's processes and mocapd live on loopback,
`mocap monitor` on mocapd's output, its page in headless Chromium. The page draws the poses
mocapd published (read back from the drawn joints, within 1 mm) and a camera box that stops
turns its stream, and its frustum, stale."""

import subprocess
import sys

import numpy as np
import pytest

from mocap import processes
from mocap.demo import browser, play
from mocap.demo import studio as live_studio
from mocap.demo.live_studio import LiveStudio

pytestmark = [pytest.mark.skipif(not play.MOCAPD.exists(), reason="mocapd is not built (make build)"),
              pytest.mark.skipif(not browser.CHROMIUM.exists(), reason="Chromium is not installed (make setup)")]

STOPPED = "cam3"


def _monitor(session) -> tuple[subprocess.Popen, str]:
    monitor = subprocess.Popen([sys.executable, "-m", "mocap.cli", "monitor", "--session", str(session),
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
        monitor, url = _monitor(studio.session)
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
