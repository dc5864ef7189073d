"""The camera box on the simulated studio's backend (`sim:` frame source and keypoint
model): the box's own loop publishes the stream file's frames with the file's capture
times and keypoints, no earlier than a box's detection would finish, skips detection in
high-speed mode, and a box unplugged for a span closes its socket and binds it again."""

import logging
import re
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import zmq
from zmq.utils.monitor import recv_monitor_message

from mocap.net import transport
from mocap.net import wire
from mocap_edge import camera_box
from mocap_edge.detect import open_detector
from mocap_edge.detect.tracking import Tracker
from mocap_edge.errors import SourceError
from mocap_edge.sources import open_source
from mocap_edge.sources.sim import MAX_FRAMES, frame_of, picture
from mocap_edge.streams import CAMERA_FIELDS, Streams

FPS = 60.0
MS = 1_000_000


def stream_file(folder: Path, frames: int, detect_every: tuple[int, int] = (1, 1), empty: tuple[int, ...] = ()) -> Path:
    """Two cameras (cam1 800 x 600) seeing a person drift 2 px a frame (its left and right
    apart: nothing for the tracker's left/right check to mirror), nobody in frames `empty`,
    no detection where the high-speed pattern skips (as the simulated studio writes them)."""
    rng = np.random.default_rng(7)
    keypoints = np.zeros((frames, 2, 33, 3), np.float32)
    pose = rng.uniform(100, 500, (2, 33, 2))
    keypoints[..., :2] = pose + 2.0 * np.arange(frames)[:, None, None, None] + rng.normal(0, 0.5, (frames, 2, 33, 2))
    keypoints[..., 2] = rng.uniform(0.5, 1.0, (frames, 2, 33))
    keypoints[list(empty)] = 0
    detected = np.arange(frames) % detect_every[0] < detect_every[1]
    keypoints[~detected] = 0
    times = np.round(np.arange(frames) * 1e9 / FPS + rng.normal(0, 0.2 * MS, frames)).astype(np.int64)
    path = folder / "streams.npz"
    Streams(["cam0", "cam1"], "blazepose33", np.array([[640, 480], [800, 600]]), times, keypoints, detected,
            ["imu0"], np.zeros(1, np.int64), np.zeros((1, 1, 4)), np.zeros((1, 1, 3))).save(path)
    return path


def free_endpoint() -> str:
    with zmq.Context.instance().socket(zmq.PUB) as s:
        return f"tcp://127.0.0.1:{s.bind_to_random_port('tcp://127.0.0.1')}"


def collect(endpoint: str, count: int, got: list) -> threading.Thread:
    sub = transport.subscriber(zmq.Context.instance(), [endpoint])

    def run():
        while len(got) < count and sub.poll(3000):
            got.append(wire.decode(sub.recv_multipart()))
        sub.close()
    thread = threading.Thread(target=run)
    thread.start()
    return thread


def test_a_picture_codes_its_frame_number_in_one_pixel() -> None:
    for f in (0, 1, 255, 256, 65_537, MAX_FRAMES - 1):
        image = picture(f, (1920, 1080))
        assert image.shape == (1080, 1920, 3) and image.dtype == np.uint8 and frame_of(image) == f
    assert picture(5, (1920, 1080)).strides[:2] == (0, 0)  # one pixel: no memory per frame
    with pytest.raises(ValueError):
        picture(MAX_FRAMES, (4, 4))


@pytest.mark.parametrize("detect_every", [(1, 1), (4, 2)])
def test_the_box_publishes_the_files_frames_when_its_detection_would_be_done(tmp_path, detect_every) -> None:
    streams = stream_file(tmp_path, 24, detect_every, empty=(5,))
    file = Streams.load(streams)
    start, endpoint, got = time.time_ns() + 500 * MS, free_endpoint(), []
    thread = collect(endpoint, 24, got)
    model = open_detector(f"sim:{streams}", camera="cam1", start_ns=start, seed=3)
    with open_source(f"sim:{streams}", camera="cam1", start_ns=start) as source:
        counts = camera_box.run(source, "cam1", endpoint, detect_every, model=model)
    thread.join(timeout=10)
    assert counts.frames == 24 and [m.frame_index for m in got] == list(range(24))
    assert [m.capture_time_ns for m in got] == list(start + file.frame_times_ns)
    assert [m.detected for m in got] == list(file.detected)
    assert {(m.image_width, m.image_height) for m in got} == {(800, 600)}
    for m in got:
        f = m.frame_index
        if m.detected and f != 5:
            np.testing.assert_array_equal(np.column_stack([m.persons[0].x, m.persons[0].y, m.persons[0].confidence]),
                                          file.keypoints[f, 1])
            assert m.send_time_ns >= model.ready_ns[f]  # capture + 6 ms + the seeded jitter
        else:
            assert len(m.persons) == 0  # nobody (frame 5), or no detection run (high-speed mode)


def test_the_detection_latency_is_seeded_per_frame(tmp_path) -> None:
    streams = stream_file(tmp_path, 3000)
    times = Streams.load(streams).frame_times_ns

    def latency_ms(seed: int) -> np.ndarray:
        return (open_detector(f"sim:{streams}", camera="cam0", start_ns=0, seed=seed).ready_ns - times) / MS
    a = latency_ms(1)
    np.testing.assert_array_equal(a, latency_ms(1))
    assert not np.array_equal(a, latency_ms(2))
    assert a.min() >= 6.0 and abs(a.mean() - 6.5) < 0.05  # 6 ms + exponential jitter, mean 0.5 ms


def test_tracking_runs_on_the_simulated_keypoints(tmp_path) -> None:
    streams = stream_file(tmp_path, 12, empty=(5,))
    tracker = Tracker(open_detector(f"sim:{streams}", camera="cam0", start_ns=0))
    with open_source(f"sim:{streams}", camera="cam0", start_ns=0) as source:
        found = [len(tracker.step({"cam0": frame.image})["cam0"]) for frame in source]
    assert found == [1] * 5 + [0] + [1] * 6
    assert tracker.counts.detector_runs == 2  # the first frame, and 6: the track was lost at 5


def test_a_frame_the_studio_did_not_detect_has_nobody_and_says_why(tmp_path, caplog) -> None:
    streams = stream_file(tmp_path, 8, detect_every=(4, 2))
    model = open_detector(f"sim:{streams}", camera="cam0", start_ns=0)
    with caplog.at_level(logging.WARNING):
        assert model.detect(picture(2, (640, 480))) == [] and model.detect(picture(3, (640, 480))) == []
    assert len(caplog.records) == 1 and "--hs" in caplog.text


def test_a_box_reads_its_cameras_part_of_a_long_take_and_maps_the_rest(tmp_path, monkeypatch) -> None:
    """A camera box reads the file's camera fields and its own keypoints; the keypoints of
    every camera and the IMUs' samples stay mapped from the file (an hour is 1.4 GB) until
    used, with the same values; a compressed file is read whole, as before."""
    monkeypatch.setattr("mocap_edge.streams.MAPPED_MIN_BYTES", 1024)
    path = stream_file(tmp_path, 600)
    whole = Streams.load(path)
    part = Streams.load(path, read=CAMERA_FIELDS)
    assert isinstance(part.keypoints, np.memmap) and not isinstance(whole.keypoints, np.memmap)
    assert isinstance(part.frame_times_ns, np.ndarray) and not isinstance(part.frame_times_ns, np.memmap)
    mine = part.camera("cam1")
    assert not isinstance(mine.keypoints, np.memmap) and mine.keypoints.base is None  # its own memory
    np.testing.assert_array_equal(mine.keypoints, whole.keypoints[:, 1])
    np.testing.assert_array_equal(mine.frame_times_ns, whole.frame_times_ns)
    np.testing.assert_array_equal(part.keypoints, whole.keypoints)
    compressed = tmp_path / "compressed.npz"
    with np.load(path) as z:
        np.savez_compressed(compressed, **{k: z[k] for k in z.files})
    again = Streams.load(compressed, read=CAMERA_FIELDS)
    assert not isinstance(again.keypoints, np.memmap)
    np.testing.assert_array_equal(again.camera("cam1").keypoints, mine.keypoints)


def test_the_simulated_source_names_what_is_wrong(tmp_path) -> None:
    streams = stream_file(tmp_path, 4)
    with pytest.raises(SourceError, match=re.escape("no camera 'cam9' in the stream file (it has cam0, cam1)")):
        open_source(f"sim:{streams}", camera="cam9")
    with pytest.raises(SourceError, match="^sim: "):
        open_source("sim:/nonexistent.npz", camera="cam0")
    (tmp_path / "junk.npz").write_bytes(b"junk")
    with pytest.raises(SourceError, match="not a stream file"):
        open_source(f"sim:{tmp_path / 'junk.npz'}", camera="cam0")


def test_an_unplugged_box_closes_its_socket_for_the_span_and_binds_again(tmp_path) -> None:
    streams = stream_file(tmp_path, 120)  # 2 s
    seconds = Streams.load(streams).frame_times_ns * 1e-9
    endpoint, start = free_endpoint(), time.time_ns() + 1500 * MS
    context = zmq.Context.instance()
    sub = transport.subscriber(context, [endpoint])
    monitor = sub.get_monitor_socket(zmq.EVENT_CONNECTED | zmq.EVENT_DISCONNECTED)
    box = subprocess.Popen([sys.executable, "-m", "mocap_edge", "camera", "--source", f"sim:{streams}",
                            "--camera", "cam1", "--bind", endpoint, "--start-ns", str(start), "--stop", "0.3", "0.6"],
                           stderr=subprocess.PIPE, text=True)
    got, events = [], []
    poller = zmq.Poller()
    poller.register(sub, zmq.POLLIN)
    poller.register(monitor, zmq.POLLIN)
    while box.poll() is None or poller.poll(500):
        for socket, _ in poller.poll(100):
            if socket is sub:
                got.append(wire.decode(sub.recv_multipart()))
            else:
                events.append((recv_monitor_message(monitor)["event"], (time.time_ns() - start) * 1e-9))
    sub.disable_monitor()
    monitor.close()
    sub.close()
    sent = int(((seconds < 0.3) | (seconds >= 0.6)).sum())
    assert box.returncode == 0 and f"cam1: {sent} frames sent, {sent} detected" in box.stderr.read()
    t = np.array([(m.capture_time_ns - start) * 1e-9 for m in got])
    assert (t < 0.3).sum() == (seconds < 0.3).sum() and not ((t >= 0.3) & (t < 0.6)).any()
    assert (t >= 0.6).any()  # the subscriber found the box again
    # disconnections once frames flowed (a handshake dropped while the box was starting, seen
    # once on CI at -1.5 s, is not the unplug)
    disconnected = [s for e, s in events if e == zmq.EVENT_DISCONNECTED and s > t.min()]
    reconnected = [s for e, s in events if e == zmq.EVENT_CONNECTED and disconnected and s > disconnected[0]]
    assert seconds[seconds < 0.3].max() < disconnected[0] < 0.6 and reconnected and reconnected[0] >= 0.6, events


def test_only_a_simulated_box_can_be_unplugged() -> None:
    out = subprocess.run([sys.executable, "-m", "mocap_edge", "camera", "--source", "fake:", "--model", "fake:",
                          "--bind", "tcp://127.0.0.1:0", "--stop", "1", "2"], capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 1 and out.stderr.startswith("mocap_edge: --stop unplugs a simulated box")


def test_a_box_started_during_the_take_captures_from_then_on_and_its_clock_can_be_stepped(tmp_path) -> None:
    """A box (re)started 1 s into the take with --from-open sends from then on, not the second
    it missed at once; --clock-step stamps its frames with a clock that reads off by the step's offset
    (a PTP loss) while they are still captured, and sent, at their time."""
    streams = stream_file(tmp_path, 180)  # 3 s
    seconds = Streams.load(streams).frame_times_ns * 1e-9
    endpoint, start = free_endpoint(), time.time_ns() - 1000 * MS
    sub = transport.subscriber(zmq.Context.instance(), [endpoint])
    box = subprocess.Popen([sys.executable, "-m", "mocap_edge", "camera", "--source", f"sim:{streams}", "--camera",
                            "cam0", "--bind", endpoint, "--start-ns", str(start), "--from-open", "--clock-step", "1.5", "1.0",
                            "--clock-step", "2.0", "-1.0", "--clock-step", "2.5", "0"], stderr=subprocess.PIPE,
                           text=True)
    got = []
    while box.poll() is None or sub.poll(500):
        if sub.poll(100):
            got.append((time.time_ns(), wire.decode(sub.recv_multipart())))
    sub.close()
    assert box.returncode == 0, box.stderr.read()
    index = np.array([m.frame_index for _, m in got])
    offset_s = np.array([(m.capture_time_ns - start) * 1e-9 - seconds[m.frame_index] for _, m in got])
    assert seconds[index.min()] > 0.9 and len(index) == index.max() - index.min() + 1  # from then on, each frame
    taken = seconds[index]
    expected = np.select([taken < 1.5, taken < 2.0, taken < 2.5], [0.0, 1.0, -1.0], 0.0)
    assert np.abs(offset_s - expected).max() < 1e-6
    sent_late_s = np.array([(t - start) * 1e-9 for t, _ in got]) - taken
    assert 0 < sent_late_s.min() and np.median(sent_late_s) < 0.1  # sent at their time, whatever the stamp
