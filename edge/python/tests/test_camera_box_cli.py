"""The camera box's command line on the in-process fake camera (no data, no hardware)."""

import subprocess
import sys


def run(*args):
    return subprocess.run([sys.executable, "-m", "mocap_edge", "camera", *args], capture_output=True, text=True,
                          timeout=120)


def test_the_box_runs_on_the_fake_camera_and_reports_what_it_sent():
    out = run("--source", "fake:", "--camera", "cam7", "--bind", "tcp://127.0.0.1:0", "--hs", "4", "1")
    assert out.returncode == 0, out.stderr
    assert "cam7: 60 frames sent, 15 detected" in out.stderr  # nobody in the fake's pictures


def test_hardware_that_is_absent_is_named_not_traced():
    for args in (["--trigger", "/dev/gpiochip9:3"], ["--trigger", "/dev/gpiochip0:x"]):
        out = run("--source", "fake:", "--bind", "tcp://127.0.0.1:0", *args)
        assert out.returncode == 1 and "Traceback" not in out.stderr and out.stderr.startswith("mocap_edge:")
    out = run("--source", "v4l2:/dev/video9", "--bind", "tcp://127.0.0.1:0")
    assert out.returncode == 1 and "Traceback" not in out.stderr


def test_mocap_detect_names_a_missing_video():
    out = subprocess.run([sys.executable, "-m", "mocap.cli", "detect", "/nonexistent.mp4", "--out", "/tmp/unused"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "no such file: /nonexistent.mp4" in out.stderr and "Traceback" not in out.stderr
