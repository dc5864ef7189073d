"""Frame sources: real files written here (a 60 fps video, PNG folders) read back through
open_source with their content and capture times; clear errors for what cannot open."""

from __future__ import annotations

import re
import shutil
import struct
import sys
import time
import types
from pathlib import Path

import cv2
import numpy as np
import pytest

from mocap_edge import clocks
from mocap_edge.errors import SourceError
from mocap_edge.sources import Frame, open_source
from mocap_edge.sources.fake import SQUARE

FPS, COUNT, WIDTH, HEIGHT = 60, 45, 160, 96
START_NS = 1_700_000_000_123_456_789
MS = 1_000_000


def red_bar_image(k: int) -> np.ndarray:
    """BGR (as OpenCV writes): a red bar 16 px wide whose left edge is at x = 3 k."""
    image = np.zeros((HEIGHT, WIDTH, 3), np.uint8)
    image[:, 3 * k:3 * k + 16] = (0, 0, 255)
    return image


def bar_x(rgb: np.ndarray) -> int:
    """Left edge of the red bar in an RGB frame (red channel above half in most rows)."""
    columns = (rgb[:, :, 0] > 128).mean(axis=0) > 0.5
    return int(np.argmax(columns))


@pytest.fixture(scope="module")
def video(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("video") / "take.mp4"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), FPS, (WIDTH, HEIGHT))
    assert writer.isOpened()
    for k in range(COUNT):
        writer.write(red_bar_image(k))
    writer.release()
    return path


def mp4_child(data: bytes, start: int, end: int, name: bytes) -> tuple[int, int]:
    """Offset and size of the first box `name` among the boxes in data[start:end]."""
    while start < end:
        size, kind = struct.unpack_from(">I4s", data, start)
        if kind == name:
            return start, size
        start += size
    raise AssertionError(f"no {name!r} box")


def delay_frames_after(path: Path, k0: int) -> None:
    """Makes frame k0 of the (single-track, constant-rate) MP4 last two frame periods, so the
    frames after it are presented one period later, as when a camera drops a frame: the
    time-to-sample table (stts) gets three runs, its parent boxes grow by the same bytes
    (moov is after mdat, so chunk offsets stay valid) and the edit list, which would cut the
    now longer track, becomes a free box."""
    data = bytearray(path.read_bytes())
    chain, start, end = [], 0, len(data)
    for name in (b"moov", b"trak", b"mdia", b"minf", b"stbl", b"stts"):
        at, size = mp4_child(data, start, end, name)
        chain.append(at)
        start, end = at + 8, at + size
    assert mp4_child(data, 0, len(data), b"mdat")[0] < chain[0]
    stts, stts_size = chain[-1], struct.unpack_from(">I", data, chain[-1])[0]
    _, runs, count, delta = struct.unpack_from(">IIII", data, stts + 8)
    assert runs == 1 and count == COUNT
    table = [(k0, delta), (1, 2 * delta), (count - k0 - 1, delta)]
    new = struct.pack(">I4sII", 16 + 8 * len(table), b"stts", 0, len(table))
    new += b"".join(struct.pack(">II", *run) for run in table)
    for at in chain[:-1]:
        struct.pack_into(">I", data, at, struct.unpack_from(">I", data, at)[0] + len(new) - stts_size)
    data[stts:stts + stts_size] = new
    trak_end = chain[1] + struct.unpack_from(">I", data, chain[1])[0]
    edts, _ = mp4_child(data, chain[1] + 8, trak_end, b"edts")
    data[edts + 4:edts + 8] = b"free"
    path.write_bytes(bytes(data))


def test_video_frames_come_back_in_order_with_container_times(video: Path) -> None:
    with open_source(f"video:{video}", start_ns=START_NS) as source:
        assert source.size == (WIDTH, HEIGHT) and source.nominal_fps == pytest.approx(FPS)
        frames = list(source)
    assert [f.index for f in frames] == list(range(COUNT))
    for k, frame in enumerate(frames):
        assert frame.image.shape == (HEIGHT, WIDTH, 3) and frame.image.dtype == np.uint8
        assert abs(frame.capture_time_ns - (START_NS + round(k * 1e9 / FPS))) <= 1 * MS
        assert abs(bar_x(frame.image) - 3 * k) <= 1  # content, and R is channel 0
        assert frame.image[:, :, 2].max() < 100  # no blue: the channels are not swapped
    assert source.dropped == 0


def test_video_times_are_the_containers_not_index_over_fps(video: Path, tmp_path: Path) -> None:
    gapped = tmp_path / "gap.mp4"
    shutil.copy(video, gapped)
    delay_frames_after(gapped, k0=9)
    with open_source(f"video:{gapped}", start_ns=START_NS) as source:
        frames = list(source)
    assert [f.index for f in frames] == list(range(COUNT))
    for k, frame in enumerate(frames):
        presented = k if k <= 9 else k + 1  # frame periods
        assert abs(frame.capture_time_ns - (START_NS + round(presented * 1e9 / FPS))) <= 1 * MS
        assert abs(bar_x(frame.image) - 3 * k) <= 1


def test_video_default_start_is_the_opening_time(video: Path) -> None:
    before = time.time_ns()
    with open_source(f"video:{video}") as source:
        first = next(iter(source))
    assert before <= first.capture_time_ns <= time.time_ns()


def test_image_folder_in_name_order_at_the_given_rate(tmp_path: Path) -> None:
    for k in range(12):  # names sort as the frame order; a stray text file is ignored
        cv2.imwrite(str(tmp_path / f"frame_{k:04d}.png"), red_bar_image(k))
    (tmp_path / "notes.txt").write_text("not an image")
    with open_source(f"images:{tmp_path}", fps=30.0, start_ns=START_NS) as source:
        frames = list(source)
    assert [f.index for f in frames] == list(range(12))
    for k, frame in enumerate(frames):
        assert frame.capture_time_ns == START_NS + round(k * 1e9 / 30)
        assert np.array_equal(frame.image, red_bar_image(k)[:, :, ::-1])  # PNG is lossless


def test_image_folder_drops_and_counts_a_bad_image(tmp_path: Path) -> None:
    cv2.imwrite(str(tmp_path / "a.png"), red_bar_image(0))
    (tmp_path / "b.png").write_bytes(b"not a png")
    cv2.imwrite(str(tmp_path / "c.png"), red_bar_image(2))
    with open_source(f"images:{tmp_path}", fps=10.0, start_ns=0) as source:
        frames = list(source)
    assert [(f.index, f.capture_time_ns) for f in frames] == [(0, 0), (2, 200 * MS)]
    assert source.dropped == 1


def test_fake_source_is_deterministic() -> None:
    def take() -> list[Frame]:
        with open_source("fake:", width=64, height=48, fps=100.0, count=5, start_ns=7) as source:
            return list(source)
    a, b = take(), take()
    assert [f.capture_time_ns for f in a] == [7 + k * 10 * MS for k in range(5)]
    assert all(np.array_equal(x.image, y.image) for x, y in zip(a, b, strict=True))
    assert [int(np.argmax(f.image[24, :, 0] == 255)) for f in a] == [4 * k for k in range(5)]
    assert a[0].image[24, 4 * 3 + SQUARE, 0] < 128  # the square is SQUARE wide


@pytest.mark.parametrize("uri, options, message", [
    ("nosuch:thing", {}, "unknown frame source 'nosuch:thing'"),
    ("take.mp4", {}, "must start with one of video:, images:, v4l2:, libcamera:, fake:"),
    ("video:/nonexistent/take.mp4", {}, "video: no such file: /nonexistent/take.mp4"),
    ("images:/nonexistent", {"fps": 30.0}, "images: no such folder: /nonexistent"),
    ("images:/tmp", {}, "images: source options: missing a required argument: 'fps'"),
    ("fake:", {"colour": "red"}, "fake: source options: got an unexpected keyword argument 'colour'"),
])
def test_clear_errors(uri: str, options: dict, message: str) -> None:
    with pytest.raises(SourceError, match=re.escape(message)):
        open_source(uri, **options)


def test_a_file_that_is_not_a_video(tmp_path: Path) -> None:
    path = tmp_path / "take.mp4"
    path.write_bytes(b"\0" * 1000)
    with pytest.raises(SourceError, match="cannot decode"):
        open_source(f"video:{path}")


def test_libcamera_without_picamera2_opens_through_the_projects_adapter() -> None:
    """Off a Raspberry Pi, `libcamera:` goes through the adapter over libcamera's C++ API
    (edge/libcamera/); a camera that is not there is a SourceError naming it and what was
    found (capturing from a real kernel camera: the VM tests' vimc)."""
    try:
        import picamera2  # noqa: F401
    except ImportError:
        pass
    else:
        pytest.skip("picamera2 is installed: this is a Raspberry Pi")
    from mocap_edge.sources import _libcamera

    found = _libcamera.list_cameras()
    with pytest.raises(SourceError, match=rf"^libcamera: no camera {len(found)} \(found {len(found)}: ") as raised:
        open_source(f"libcamera:{len(found)}")
    assert raised.value.__suppress_context__  # the adapter's error, without its traceback
    with pytest.raises(SourceError, match="no camera no-such-id"):
        open_source("libcamera:no-such-id")
    with pytest.raises(SourceError, match="out of range"):
        open_source("libcamera:0", fps=0.0)
    assert _libcamera.version().count(".") == 2


def test_libcamera_without_either_backend_says_what_is_missing(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "picamera2", None)  # import fails
    monkeypatch.setitem(sys.modules, "mocap_edge.sources._libcamera", None)
    with pytest.raises(SourceError) as raised:
        open_source("libcamera:0")
    assert "apt install python3-picamera2" in str(raised.value) and "libcamera-dev" in str(raised.value)
    assert raised.value.__suppress_context__  # the ImportError's traceback is not chained


def test_v4l2_fails_clearly_without_a_device() -> None:
    device = "/dev/video99"
    assert not Path(device).exists()
    with pytest.raises(SourceError, match=f"^v4l2: no camera device at {device} ") as raised:
        open_source(f"v4l2:{device}")
    assert raised.value.__context__ is None


def test_realtime_offset_of_the_monotonic_clock() -> None:
    offset = clocks.realtime_offset_ns(time.CLOCK_MONOTONIC)
    assert abs(time.clock_gettime_ns(time.CLOCK_MONOTONIC) + offset - time.time_ns()) < MS


def test_libcamera_times_from_request_metadata(monkeypatch: pytest.MonkeyPatch) -> None:
    """The adapter's arithmetic against a stand-in picamera2 module (no camera here): the
    Pi's SensorTimestamp (CLOCK_MONOTONIC, end of the first row's exposure) minus half the
    ExposureTime (us), moved to CLOCK_REALTIME."""
    exposure_us, sensor_ns = 8000, time.clock_gettime_ns(time.CLOCK_MONOTONIC) - 30 * MS
    released = []

    class Request:
        def make_array(self, stream: str) -> np.ndarray:
            return np.zeros((HEIGHT, WIDTH, 3), np.uint8)

        def get_metadata(self) -> dict:
            return {"SensorTimestamp": sensor_ns, "ExposureTime": exposure_us}

        def release(self) -> None:
            released.append(True)

    class Picamera2:
        def __init__(self, number: int) -> None:
            assert number == 1

        def create_video_configuration(self, **config: object) -> dict:
            assert config["main"] == {"size": (WIDTH, HEIGHT), "format": "BGR888"}
            return config

        def configure(self, config: dict) -> None:
            self.config = config

        start = stop = close = lambda self: None  # noqa: E731 (no camera to drive)

        def capture_request(self) -> Request:
            return Request()

    monkeypatch.setitem(sys.modules, "picamera2", types.SimpleNamespace(Picamera2=Picamera2))
    with open_source("libcamera:1", width=WIDTH, height=HEIGHT, fps=30.0) as source:
        frame = next(iter(source))
    expected = sensor_ns - exposure_us * 500 + time.time_ns() - time.clock_gettime_ns(time.CLOCK_MONOTONIC)
    assert abs(frame.capture_time_ns - expected) < MS and released == [True]
