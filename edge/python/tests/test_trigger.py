"""Trigger timestamps: FakeTrigger edges paired with frames of the fake camera whose own
times are jittered; missed and late-read edges; clear errors without a GPIO chip."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import pytest

from mocap_edge.errors import TriggerError
from mocap_edge.sources import Frame, open_source
from mocap_edge.trigger import FakeTrigger, GpiodTrigger, GpiodTriggerOutput, TriggerPairing

RATE, COUNT = 60.0, 30
START_NS = 1_700_000_000_000_000_000
MS = 1_000_000
EVER = 2**62  # a clock at which every fake edge is readable (so give the train a count)


def camera_frames(trigger: FakeTrigger, latency_ns: int = 0, jitter_ms: tuple[float, ...] = (3, -2, 1, -3, 2),
                  skip: tuple[int, ...] = ()) -> list[Frame]:
    """The fake camera's frames k = 0.. exposed on edge k, stamped by the box's own clock:
    the edge time + latency + a few ms of jitter (cycling through jitter_ms)."""
    with open_source("fake:", width=32, height=24, fps=RATE, count=COUNT) as source:
        frames = list(source)
    return [dataclasses.replace(f, capture_time_ns=trigger.edge_time(f.index) + latency_ns
                                + round(jitter_ms[f.index % len(jitter_ms)] * MS))
            for f in frames if f.index not in skip]


def test_jittered_frames_take_their_edges_time_and_count() -> None:
    trigger = FakeTrigger(RATE, START_NS, jitter_ns=200_000, seed=1, count=COUNT, clock=lambda: EVER)
    frames = camera_frames(trigger)
    pairing = TriggerPairing(trigger, RATE)
    paired = list(pairing.pair(frames))
    assert [f.index for f in paired] == list(range(COUNT))
    assert [f.capture_time_ns for f in paired] == [trigger.edge_time(k) for k in range(COUNT)]
    assert [f.image is g.image for f, g in zip(paired, frames, strict=True)] == [True] * COUNT
    assert dataclasses.astuple(pairing.counts) == (COUNT, 0, 0, 0)
    edges = [trigger.edge_time(k) - START_NS - k * trigger.period_ns for k in range(COUNT)]
    assert max(map(abs, edges)) <= 200_000 and len(set(edges)) > 1  # jittered, within bounds


def test_a_missed_edge_leaves_its_frame_unpaired_and_the_count_keeps_going() -> None:
    trigger = FakeTrigger(RATE, START_NS, jitter_ns=100_000, missed={7}, count=COUNT, clock=lambda: EVER)
    pairing = TriggerPairing(trigger, RATE)
    paired = list(pairing.pair(camera_frames(trigger)))
    assert [f.index for f in paired] == [k for k in range(COUNT) if k != 7]  # 8 follows 6: the gap is seen
    assert [f.capture_time_ns for f in paired] == [trigger.edge_time(k) for k in range(COUNT) if k != 7]
    assert dataclasses.astuple(pairing.counts) == (COUNT - 1, 1, 0, 0)


def test_a_dropped_frame_leaves_its_edge_unused() -> None:
    trigger = FakeTrigger(RATE, START_NS, count=COUNT, clock=lambda: EVER)
    pairing = TriggerPairing(trigger, RATE)
    paired = list(pairing.pair(camera_frames(trigger, skip=(3, 4))))
    assert [f.index for f in paired] == [k for k in range(COUNT) if k not in (3, 4)]
    assert dataclasses.astuple(pairing.counts) == (COUNT - 2, 0, 2, 0)


class Edges(FakeTrigger):
    """FakeTrigger's edges and extra ones (a glitch on the line)."""

    def __init__(self, extra: list[int], **options) -> None:
        super().__init__(**options)
        self.extra = extra

    def read_edges(self, timeout_s: float = 0.0) -> list[int]:
        edges, self.extra = sorted(super().read_edges(timeout_s) + self.extra), []
        return edges


def test_a_spurious_edge_is_counted_and_the_count_keeps_right() -> None:
    trigger = Edges([START_NS + round(6.4e9 / RATE)], rate_hz=RATE, start_ns=START_NS, count=COUNT,
                    clock=lambda: EVER)
    pairing = TriggerPairing(trigger, RATE)
    paired = list(pairing.pair(camera_frames(trigger)))
    assert [f.index for f in paired] == list(range(COUNT))
    assert [f.capture_time_ns for f in paired] == [trigger.edge_time(k) for k in range(COUNT)]
    assert dataclasses.astuple(pairing.counts) == (COUNT, 0, 0, 1)


def test_an_edge_read_after_its_frame_still_pairs() -> None:
    now = [0]
    trigger = FakeTrigger(RATE, START_NS, jitter_ns=100_000, seed=3, count=COUNT, clock=lambda: now[0])
    frames = camera_frames(trigger)
    pairing = TriggerPairing(trigger, RATE, max_pending=2)
    paired = []
    for frame in frames:  # each frame arrives while its edge is still unread
        now[0] = trigger.edge_time(frame.index) - 1
        paired += pairing.add(frame)
        assert len(paired) == frame.index  # the frames before it, not yet this one
    now[0] = EVER
    paired += pairing.flush()
    assert [(f.index, f.capture_time_ns) for f in paired] == [(k, trigger.edge_time(k)) for k in range(COUNT)]
    assert dataclasses.astuple(pairing.counts) == (COUNT, 0, 0, 0)


def test_frames_wait_for_edges_only_up_to_max_pending() -> None:
    trigger = FakeTrigger(RATE, START_NS, clock=lambda: 0)  # the line is dead: no edge is ever read
    pairing = TriggerPairing(trigger, RATE, max_pending=3)
    out = [pairing.add(f) for f in camera_frames(trigger)[:5]]
    assert out == [[]] * 5 and pairing.counts.unpaired_frames == 2
    assert pairing.flush() == [] and pairing.counts.unpaired_frames == 5


def test_a_constant_latency_is_taken_out_by_the_offset() -> None:
    trigger = FakeTrigger(RATE, START_NS, count=COUNT, clock=lambda: EVER)
    frames = camera_frames(trigger, latency_ns=25 * MS)  # 1.5 periods after the edge, +-3 ms
    unaligned = TriggerPairing(trigger, RATE)
    assert list(unaligned.pair(frames)) == [] and unaligned.counts.unpaired_frames == COUNT
    trigger = FakeTrigger(RATE, START_NS, count=COUNT, clock=lambda: EVER)
    pairing = TriggerPairing(trigger, RATE, offset_ns=25 * MS)
    assert [(f.index, f.capture_time_ns) for f in pairing.pair(frames)] == \
        [(k, trigger.edge_time(k)) for k in range(COUNT)]


def test_fake_trigger_is_deterministic_and_ends() -> None:
    a = FakeTrigger(RATE, START_NS, jitter_ns=500_000, seed=9, count=10, clock=lambda: EVER)
    b = FakeTrigger(RATE, START_NS, jitter_ns=500_000, seed=9, count=10, clock=lambda: EVER)
    edges = a.read_edges()
    assert edges == b.read_edges() and len(edges) == 10 and edges == sorted(edges)
    assert a.read_edges(timeout_s=0.01) == []


@pytest.mark.parametrize("make", [lambda chip: GpiodTrigger(chip, 17),
                                  lambda chip: GpiodTriggerOutput(chip, 17, RATE)])
def test_gpiod_without_a_chip_fails_clearly(make: Callable[[str], object]) -> None:
    with pytest.raises(TriggerError, match=r"^no GPIO chip at /dev/gpiochip99 \(gpiodetect") as raised:
        make("/dev/gpiochip99")
    assert raised.value.__suppress_context__
    with pytest.raises(TriggerError, match=r"^cannot request GPIO line 17 of /dev/null: "):
        make("/dev/null")  # a device, but not a GPIO chip
