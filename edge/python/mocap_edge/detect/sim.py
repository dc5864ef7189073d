"""The simulated studio's keypoint model, `sim:STREAMS`: what the simulated detector found
on one camera (the stream file's keypoints, simulated errors included), for the pictures
of the sim: frame source (sources/sim.py), whose colour codes the frame number.

It answers no earlier than the detection would have finished on the box: the frame's
capture time + `latency_ms` + an exponential jitter of mean `jitter_ms`, drawn per frame
from `seed` — so the live figures (arrival times at the host, its latency) are measured
with a box's timing. A person is wherever the file has a keypoint with confidence > 0
(presence 1), in an upright region around its keypoints; a frame the file has no
detection for (the studio ran in high-speed mode: run the box with the same `--hs`)
has nobody, with a warning.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from mocap_edge import pacing
from mocap_edge.detect import layouts
from mocap_edge.detect.base import Crop, Detector, Person
from mocap_edge.detect.roi import Roi
from mocap_edge.errors import ModelError
from mocap_edge.sources.sim import frame_of, load_camera

log = logging.getLogger(__name__)
PADDING = 1.25  # region side / the larger side of the keypoints' box


class SimulatedDetector(Detector):
    """Camera `camera` of the stream file `streams`, whose take started at `start_ns` (as
    given to the sim: source; default now)."""

    def __init__(self, streams: str, camera: str, start_ns: int | None = None, latency_ms: float = 6.0,
                 jitter_ms: float = 0.5, seed: int = 0, min_presence: float = 0.5) -> None:
        try:
            self.stream = load_camera(streams, camera)
        except (OSError, ValueError) as e:
            raise ModelError(f"sim: {e}") from None
        super().__init__(layouts.load(self.stream.layout), min_presence)
        start_ns = time.time_ns() if start_ns is None else start_ns
        jitter_ms = np.random.default_rng(seed).exponential(jitter_ms, len(self.stream.frame_times_ns))
        self.ready_ns = start_ns + self.stream.frame_times_ns + (1e6 * (latency_ms + jitter_ms)).astype(np.int64)
        self._warned = False

    def detect(self, image: np.ndarray) -> list[Roi]:
        person = self._answer(image)
        return [] if person is None else [person.next_roi]

    def _landmarks(self, crops: list[Crop]) -> list[Person]:
        nobody = np.zeros((len(self.layout), 3), np.float32)
        return [self._answer(image) or Person(nobody, 0.0, region) for image, region in crops]

    def _answer(self, image: np.ndarray) -> Person | None:
        """The person the file has for the picture's frame, once its detection is done."""
        f = frame_of(image)
        if f >= len(self.ready_ns):
            log.warning("sim: a picture codes frame %d, the file has %d: not a sim: picture?", f, len(self.ready_ns))
            return None
        pacing.sleep_until(int(self.ready_ns[f]))
        if not self.stream.detected[f]:
            self._warn_undetected(f)
            return None
        keypoints = self.stream.keypoints[f]
        seen = keypoints[keypoints[:, 2] > 0, :2]
        return Person(keypoints, 1.0, _region(seen)) if len(seen) else None

    def _warn_undetected(self, f: int) -> None:
        if not self._warned:
            self._warned = True
            log.warning("sim: frame %d has no simulated detection (the studio ran in high-speed mode): run the box "
                        "with the studio's --hs", f)


def _region(points: np.ndarray) -> Roi:
    lo, hi = points.min(axis=0), points.max(axis=0)
    return Roi((lo + hi) / 2.0, float(max((hi - lo).max(), 1.0)) * PADDING)
