"""vimc, the harness's self-check (not a test of the project's code: the libcamera capture
adapter that `libcamera:` sources will use is not written yet): after udev, libcamera 0.0.3's
`cam` lists vimc's sensor and captures frames from it, so the adapter can be tested here."""

from __future__ import annotations

import re

from conftest import sh


def test_self_check_libcamera_lists_and_captures_vimc():
    listed = sh("cam", "-l").stdout
    assert re.search(r"^1: .*Sensor B", listed, re.MULTILINE), f"cam -l lists no vimc sensor:\n{listed}"
    captured = sh("cam", "-c", "1", "--capture=3").stdout
    sequences = [int(s) for s in re.findall(r"seq: (\d+)", captured)]
    assert len(sequences) == 3 and sequences == sorted(sequences), f"cam -c 1 --capture=3:\n{captured}"
