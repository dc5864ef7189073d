"""GPIO trigger: the camera box's GpiodTrigger (libgpiod v2) on the gpio-sim line `trigger` of
the chip labelled `cam-trigger` (tests/vm/stage2.sh made it through configfs). The test drives
rising edges through gpio-sim's sysfs `pull` attribute, as a trigger master's pulse would;
the kernel timestamps each (CLOCK_REALTIME) and the box pairs them with frames
(TriggerPairing). gpio-sim has no electrical timing: an edge is the instant of the write."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

LABEL, NAME = "cam-trigger", "trigger"
SIM = Path("/sys/kernel/config/gpio-sim/vm")
RATE_HZ, PERIOD_NS = 10.0, 100_000_000
MISSED, SPURIOUS_AFTER = 4, 6  # no pulse for frame 4; a glitch 0.3 period after pulse 6


@pytest.fixture(scope="module")
def line() -> tuple[str, int, Path]:
    """(chip device, line offset, its gpio-sim `pull` file), the chip found by its label."""
    import gpiod

    for device in sorted(Path("/dev").glob("gpiochip*")):
        with gpiod.Chip(str(device)) as chip:
            if chip.get_info().label == LABEL:
                offset = chip.line_offset_from_id(NAME)
                platform = Path("/sys/devices/platform") / (SIM / "dev_name").read_text().strip()
                bank = (SIM / "bank0" / "chip_name").read_text().strip()
                return str(device), offset, platform / bank / f"sim_gpio{offset}" / "pull"
    pytest.fail(f"no GPIO chip labelled {LABEL!r} among {sorted(Path('/dev').glob('gpiochip*'))}")


def pulse(pull: Path) -> tuple[int, int]:
    """A rising then a falling edge; the CLOCK_REALTIME span in which the rising one happened."""
    before = time.time_ns()
    pull.write_text("pull-up")
    after = time.time_ns()
    pull.write_text("pull-down")
    return before, after


def drive(pull: Path, count: int) -> tuple[dict[int, tuple[int, int]], int, int]:
    """Pulses k = 0..count-1 one period apart, but none for MISSED and a glitch after
    SPURIOUS_AFTER: ({k: span of its rising edge}, the first pulse's planned time, the glitch's time)."""
    start, spans, glitch = time.time_ns() + PERIOD_NS, {}, 0
    for k in range(count):
        time.sleep(max(0.0, (start + k * PERIOD_NS - time.time_ns()) * 1e-9))
        if k != MISSED:
            spans[k] = pulse(pull)
        if k == SPURIOUS_AFTER:
            time.sleep(max(0.0, (spans[k][0] + 0.3 * PERIOD_NS - time.time_ns()) * 1e-9))
            glitch = pulse(pull)[0]
    return spans, start, glitch


def test_the_trigger_timestamps_driven_edges_and_pairs_them_with_frames(line):
    import numpy as np

    from mocap_edge.sources.base import Frame
    from mocap_edge.trigger import GpiodTrigger, TriggerPairing

    device, offset, pull = line
    pull.write_text("pull-down")
    with GpiodTrigger(device, offset) as trigger:
        assert trigger.read_edges(0.0) == []
        spans, start, glitch = drive(pull, 10)
        # the camera's frames: exposed on each pulse (frame MISSED too: its pulse never came), stamped 3 ms later
        image = np.zeros((2, 2, 3), np.uint8)
        frames = [Frame(image, k, (spans[k][0] if k in spans else start + k * PERIOD_NS) + 3_000_000)
                  for k in range(10)]
        pairing = TriggerPairing(trigger, RATE_HZ)
        time.sleep(0.2)
        paired = list(pairing.pair(frames))
        lost = trigger.lost_edges
    assert [f.index for f in paired] == [k for k in range(10) if k != MISSED], "trigger counts"
    for frame in paired:  # the kernel's time of the edge, not the time it was read (a second later)
        before, after = spans[frame.index]
        assert before <= frame.capture_time_ns <= after, (frame.index, before, frame.capture_time_ns, after)
    counts = pairing.counts
    assert (counts.paired, counts.unpaired_frames, counts.unused_edges, counts.spurious_edges, lost) == \
        (9, 1, 0, 1, 0), f"{counts}, lost {lost}, glitch at {(glitch - spans[SPURIOUS_AFTER][0]) / PERIOD_NS} periods"


def test_a_line_another_process_holds_is_a_busy_error_naming_it(line):
    from mocap_edge.errors import TriggerError
    from mocap_edge.trigger import GpiodTrigger

    device, offset, _ = line
    hold = (f"import gpiod, time; r = gpiod.request_lines({device!r}, consumer='other-box', config={{{offset}: None}});"
            "print('held', flush=True); time.sleep(120)")
    other = subprocess.Popen([sys.executable, "-c", hold], stdout=subprocess.PIPE, text=True)
    try:
        assert other.stdout.readline().strip() == "held"
        with pytest.raises(TriggerError, match=f"line {offset} of {device} is busy: the consumer 'other-box'"):
            GpiodTrigger(device, offset)
    finally:
        other.kill()
        other.wait()
        other.stdout.close()
    with GpiodTrigger(device, offset):  # free again once its holder ended
        pass


def test_a_chip_or_line_that_is_not_there_is_an_error_naming_it(line):
    from mocap_edge.errors import TriggerError
    from mocap_edge.trigger import GpiodTrigger

    with pytest.raises(TriggerError, match="no GPIO chip at /dev/gpiochip9"):
        GpiodTrigger("/dev/gpiochip9", 0)
    with pytest.raises(TriggerError, match=f"cannot request GPIO line 8 of {line[0]}"):
        GpiodTrigger(line[0], 8)  # the chip has lines 0..7
