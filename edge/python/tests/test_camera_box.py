"""The camera box end to end on a real video: frames -> detector with tracking ->
KeypointFrame over ZeroMQ, high-speed mode clocking the undetected frames."""

import itertools
import threading
import time

import numpy as np
import pytest
import zmq

from mocap.eval import edge_detector as evaluation
from mocap.io.demo_data import TRIAL_CACHE, TRIAL_DONE
from mocap.net import transport, wire
from mocap_edge import camera_box
from mocap_edge.sources.base import open_source

pytestmark = pytest.mark.skipif(not (TRIAL_CACHE / TRIAL_DONE).is_file(),
                                reason="the real trial is not in .cache/ (make setup fetches it from PyPI)")


def _free_endpoint() -> str:
    with zmq.Context.instance().socket(zmq.PUB) as s:
        port = s.bind_to_random_port("tcp://127.0.0.1")
    return f"tcp://127.0.0.1:{port}"


def test_the_box_publishes_every_frame_and_detects_on_the_high_speed_subset():
    endpoint, got, start = _free_endpoint(), [], 1_763_900_000_000_000_000
    sub = transport.subscriber(zmq.Context.instance(), [endpoint])

    def collect():
        while len(got) < 16 and sub.poll(10_000):
            got.append(wire.decode(sub.recv_multipart()))

    def frames():  # the subscriber joins before the first frame
        time.sleep(0.5)
        with open_source(f"video:{TRIAL_CACHE / 'videos' / 'cam01.mp4'}", start_ns=start) as source:
            yield from itertools.islice(source, 16)

    thread = threading.Thread(target=collect)
    thread.start()
    counts = camera_box.run(frames(), "cam_01", endpoint, detect_every=(8, 2))
    thread.join(timeout=60)
    sub.close()
    assert counts.frames == 16 and counts.detected == 4
    assert [m.frame_index for m in got] == list(range(16))
    assert [m.detected for m in got] == [k % 8 < 2 for k in range(16)]
    assert max(abs(m.capture_time_ns - start - m.frame_index * 1e9 / 60) for m in got) < 1e6  # the video's PTS
    first = got[0]
    assert first.keypoint_layout == "blazepose33" and first.image_width == 1080 and len(first.persons) >= 1
    person = max(first.persons, key=lambda p: np.ptp(np.array(p.y)))
    ours = np.column_stack([person.x, person.y])[evaluation.COCO_FROM_BLAZEPOSE]
    truth = evaluation.openpose_subjects(TRIAL_CACHE, 1)[0][:17]
    d = np.linalg.norm(ours - truth[:, :2], axis=1)[truth[:, 2] > 0]
    assert np.median(d) < 0.05 * evaluation.box_size(truth)
