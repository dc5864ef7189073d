"""The camera box's command line on the in-process fake camera (no data, no hardware)."""

import subprocess
import sys


def run(*args):
    return subprocess.run([sys.executable, "-m", "mocap_edge", "camera", *args], capture_output=True, text=True,
                          timeout=120)


def test_the_box_runs_on_the_fake_camera_and_reports_what_it_sent():
    out = run("--source", "fake:", "--camera", "cam7", "--bind", "tcp://127.0.0.1:0", "--hs", "4", "1")
    assert out.returncode == 0, out.stderr
    assert "cam7: 60 frames sent, 15 detected, 0 people" in out.stderr  # BlazePose: nobody in the fake's pictures
    out = run("--source", "fake:", "--model", "fake:", "--camera", "cam7", "--bind", "tcp://127.0.0.1:0", "--hs", "4",
              "1")
    assert out.returncode == 0, out.stderr
    assert "cam7: 60 frames sent, 15 detected, 15 people" in out.stderr  # the fake model: the red square


def test_hardware_that_is_absent_is_named_not_traced():
    for args in (["--source", "fake:", "--trigger", "/dev/gpiochip9:3"], ["--source", "v4l2:/dev/video9"],
                 ["--source", "fake:", "--model", "nosuch"], ["--source", "libcamera:9"]):
        out = run(*args, "--bind", "tcp://127.0.0.1:0")
        assert out.returncode == 1 and "Traceback" not in out.stderr and out.stderr.startswith("mocap_edge:")


def test_a_malformed_setting_is_a_usage_error_before_any_device_is_opened():
    for args, said in ((["--source", "fake:", "--trigger", "/dev/gpiochip0:x"], "expected CHIP:LINE"),
                       (["--source", "libcamera:0", "--size", "640by480"], "expected WIDTHxHEIGHT"),
                       (["--source", "fake:", "--size", "640x480"], "--size is for a camera"),
                       (["--source", "fake:", "--camera", ""], "--camera is empty"),
                       (["--source", "fake:", "--max-people", "0"], "--max-people must be at least 1"),
                       (["--source", "fake:", "--redetect-every", "-1"], "--redetect-every 0 or more")):
        out = run(*args, "--bind", "tcp://127.0.0.1:0")
        assert out.returncode == 2 and "Traceback" not in out.stderr and "mocap_edge: error: " in out.stderr
        assert said in out.stderr


def test_mocap_detect_names_a_missing_video():
    out = subprocess.run([sys.executable, "-m", "mocap.cli", "detect", "/nonexistent.mp4", "--out", "/tmp/unused"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "no such file: /nonexistent.mp4" in out.stderr and "Traceback" not in out.stderr


def test_paired_frames_carry_the_mid_exposure_time_of_their_trigger_edge():
    import threading

    import zmq

    from mocap.net import transport
    from mocap.net import wire
    from mocap_edge import camera_box
    from mocap_edge.sources.base import open_source
    from mocap_edge.trigger import FakeTrigger, TriggerPairing

    start = 1_763_900_000_000_000_000
    trigger = FakeTrigger(60.0, start_ns=start + 300_000, jitter_ns=50_000, count=12, clock=lambda: start + 10**10)
    pairing = TriggerPairing(trigger, 60.0)
    with zmq.Context.instance().socket(zmq.PUB) as probe:
        endpoint = f"tcp://127.0.0.1:{probe.bind_to_random_port('tcp://127.0.0.1')}"
    sub, got = transport.subscriber(zmq.Context.instance(), [endpoint]), []

    def collect():
        while len(got) < 10 and sub.poll(10_000):
            got.append(wire.decode(sub.recv_multipart()))

    def frames():  # the fake camera's clock: frame k at start + k / 60 s
        import time
        time.sleep(0.5)
        with open_source("fake:", start_ns=start, count=10) as source:
            yield from source

    thread = threading.Thread(target=collect)
    thread.start()
    camera_box.run(frames(), "cam0", endpoint, pairing=pairing, exposure_mid_ns=2_000_000)
    thread.join(timeout=60)
    sub.close()
    assert [m.frame_index for m in got] == list(range(10))
    for m in got:  # the edge's time (with its jitter), then half a 4 ms exposure
        assert m.capture_time_ns == trigger.edge_time(m.frame_index) + 2_000_000
