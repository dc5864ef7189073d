"""vimc (a media-controller camera pipeline in the kernel, driven by libcamera's vimc pipeline
handler) through the camera box: `python -m mocap_edge camera --source libcamera:0` opens it
through the project's libcamera adapter (edge/libcamera), runs the detector on the frames and
publishes a KeypointFrame per frame. vimc sets each buffer's time with ktime_get_ns()
(CLOCK_MONOTONIC) when it fills it, and sleeps HZ/60 (16 ms at Debian's HZ=250) between
frames on top of its own processing, so its frame period is at least 16 ms and not fixed."""

from __future__ import annotations

import re
import time

from conftest import START_S, Messages, mocap_edge, sh, stop

ENDPOINT = "ipc:///tmp/vm-camera-box"
FRAMES = 12
VIMC_SLEEP_S = 4 / 250  # schedule_timeout(HZ / 60) at HZ=250: 4 jiffies


def test_self_check_libcamera_lists_vimc():
    """The harness's own check (udev ran, the modules loaded): `cam` sees vimc's sensor."""
    listed = sh("cam", "-l").stdout
    assert re.search(r"^1: .*Sensor B", listed, re.MULTILINE), f"cam -l lists no vimc sensor:\n{listed}"


def test_the_camera_box_captures_vimc_frames_and_publishes_each():
    messages = Messages(ENDPOINT)
    opened_ns = time.time_ns()
    box = mocap_edge("camera", "--source", "libcamera:0", "--size", "640x480", "--camera", "cam0",
                     "--bind", ENDPOINT, "--model", "fake:", "--hs", "4", "1")
    try:
        got = messages.until(lambda got: sum(type(m).__name__ == "KeypointFrame" for m in got) >= FRAMES,
                             START_S, box)
    finally:
        err = stop(box)
        messages.close()
    frames = [m for m in messages.got if type(m).__name__ == "KeypointFrame"][:FRAMES]
    assert got, f"{len(frames)} frames from the box; its log:\n{err}"
    assert "Traceback" not in err, err
    # every frame, in order, numbered by the camera's sequence without a gap
    assert [f.frame_index for f in frames] == list(range(frames[0].frame_index, frames[0].frame_index + FRAMES))
    assert [f.detected for f in frames] == [(f.frame_index % 4) == 0 for f in frames]  # --hs 4 1
    # times from the kernel's buffer timestamps, moved to the shared timebase: after the box
    # was started, before the frame arrived here, increasing by at least vimc's sleep
    times = [f.capture_time_ns for f in frames]
    assert opened_ns < times[0] and times[-1] < time.time_ns()
    spacing_s = [(b - a) * 1e-9 for a, b in zip(times, times[1:])]
    assert min(spacing_s) >= 0.9 * VIMC_SLEEP_S, spacing_s


def test_the_adapter_gives_vimcs_colour_bars_in_rgb_order():
    """vimc's sensor draws 75% colour bars (white, yellow, cyan, green, magenta, red, blue,
    black); after its debayer the adapter must hand them over as R, G, B. The size is what
    vimc's scaler allows nearest to the request (636 x 480 for 640 x 480)."""
    from mocap_edge.sources import open_source

    with open_source("libcamera:0", width=640, height=480) as source:
        image = next(iter(source)).image
    height, width, _ = image.shape
    assert (height, 600 <= width <= 640) == (480, True), image.shape
    bars = [image[height // 2, int((k + 0.5) * width / 8)].astype(int) for k in range(8)]
    white, red, blue = bars[0], bars[5], bars[6]
    assert min(white) > 150 and red[0] > 150 and max(red[1:]) < 50 and blue[2] > 150 and max(blue[:2]) < 50, bars


def test_a_camera_in_use_or_absent_is_an_error_naming_it():
    from mocap_edge.sources import _libcamera

    holder = _libcamera.Capture("0", 640, 480, 30.0, 4)
    try:
        box = mocap_edge("camera", "--source", "libcamera:0", "--camera", "cam0", "--bind", ENDPOINT)
        _, err = box.communicate(timeout=START_S)
        assert box.returncode == 1 and "/dev/media0 in use by another process" in err and "Traceback" not in err, err
    finally:
        holder.close()
    box = mocap_edge("camera", "--source", "libcamera:5", "--camera", "cam0", "--bind", ENDPOINT)
    _, err = box.communicate(timeout=START_S)
    assert box.returncode == 1 and "no camera 5 (found 1: " in err and "Traceback" not in err, err
