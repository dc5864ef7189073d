"""Keypoint models: the interface the tracker uses, the registry that opens them by name,
the in-process fake, and the top-down model's configured presence threshold."""

import json
import re
from pathlib import Path

import numpy as np
import pytest

from mocap_edge.detect import Detector, Person, open_detector
from mocap_edge.detect.fake import FakeDetector
from mocap_edge.detect.layouts import load as load_layout
from mocap_edge.detect.roi import Roi
from mocap_edge.detect.topdown import ModelConfig, TopDownModel
from mocap_edge.detect.tracking import Tracker
from mocap_edge.errors import ModelError
from mocap_edge.sources import open_source

LANDMARKS_ONNX = Path(__file__).resolve().parents[2] / "models" / "blazepose" / "pose_landmark_full.onnx"


def fake_frames(count: int = 10, **options) -> list:
    with open_source("fake:", count=count, **options) as source:
        return list(source)


@pytest.mark.parametrize("spec, options, message", [
    ("nosuch", {}, "unknown keypoint model 'nosuch': the name must be one of blazepose:, topdown:, sim:, fake:"),
    ("fake:", {"colour": "red"}, "fake: keypoint model options: got an unexpected keyword argument 'colour'"),
    ("/nonexistent/model.json", {}, "/nonexistent/model.json: not a model configuration"),
    ("sim:/nonexistent.npz", {"camera": "cam0"}, "sim: "),
    ("sim:/nonexistent.npz", {}, "sim: keypoint model options: missing a required argument: 'camera'"),
    ("fake:", {"min_presence": 1.5}, "min_presence must be in [0, 1], got 1.5"),
])
def test_models_open_by_name_or_say_why_not(spec: str, options: dict, message: str) -> None:
    with pytest.raises(ModelError, match=re.escape(message)):
        open_detector(spec, **options)


def test_a_backend_fills_in_only_the_primitives() -> None:
    calls = []

    class OneDot(Detector):
        def detect(self, image):
            return [Roi(np.array([5.0, 5.0]), 4.0)]

        def _landmarks(self, crops):
            calls.append(len(crops))
            return [Person(np.ones((33, 3)), 0.9, region) for _, region in crops]

    model = OneDot(load_layout("blazepose33"))
    assert model.landmarks([]) == [] and calls == []  # no inference for no crops
    image = np.zeros((10, 10, 3), np.uint8)
    assert len(model.landmarks([(image, r) for r in model.detect(image)])) == 1 and calls == [1]
    with pytest.raises(TypeError):
        Detector(load_layout("blazepose33"))  # abstract


def test_a_backend_that_loses_a_crop_is_caught() -> None:
    class Lossy(FakeDetector):
        def _landmarks(self, crops):
            return []

    image = fake_frames(1)[0].image
    with pytest.raises(RuntimeError, match="returned 0 people for 1 crops"):
        Lossy().landmarks([(image, Roi(np.array([10.0, 10.0]), 8.0))])


def test_the_fake_model_tracks_the_fake_cameras_square_and_finds_it_again_after_a_jump() -> None:
    frames = fake_frames(80, width=200, step=4)  # the square wraps to x = 0 at frame 46
    tracker = Tracker(open_detector("fake:"))
    for frame in frames:
        people = tracker.step({"cam": frame.image})["cam"]
        square_x = (4 * frame.index) % (200 - 16)
        if frame.index != 46:  # the jump: the tracked region holds no red, the person is lost
            assert len(people) == 1, frame.index
            np.testing.assert_allclose(people[0].keypoints[0], [square_x + 8, 120, 1.0])
    assert tracker.counts.detector_runs == 2  # the first frame, and after the jump


class TwoSquares(FakeDetector):
    """Finds each half of the image's red square separately: two people when both halves hold one."""

    def detect(self, image: np.ndarray) -> list[Roi]:
        found = []
        for half in (slice(0, image.shape[1] // 2), slice(image.shape[1] // 2, None)):
            masked = np.zeros_like(image)
            masked[:, half] = image[:, half]
            found += super().detect(masked)
        return found


def _squares(n: int, newcomer_from: int) -> list[np.ndarray]:
    """n images of one red square on the left, a second on the right from newcomer_from on."""
    images = []
    for i in range(n):
        image = np.zeros((120, 200, 3), np.uint8)
        image[50:66, 20:36] = (255, 0, 0)
        if i >= newcomer_from:
            image[50:66, 150:166] = (255, 0, 0)
        images.append(image)
    return images


def test_a_newcomer_is_found_while_others_are_tracked_only_when_the_detector_looks_again() -> None:
    for every, found_at in ((5, 10), (0, None)):
        tracker = Tracker(TwoSquares(), max_people=4, redetect_every=every)
        counts = [len(tracker.step({"cam": image})["cam"]) for image in _squares(30, newcomer_from=8)]
        # the detector looks at frames 0, 5, 10, ...: the newcomer of frame 8 is found at 10;
        # without looking again it never is, as the first person is never lost
        assert counts[:8] == [1] * 8
        assert counts[8:] == ([1] * (found_at - 8) + [2] * (30 - found_at) if found_at else [1] * 22), (every, counts)


class OneBehindAnother(FakeDetector):
    """Two people whose regions' centres lie a fifth of a region apart, one behind the other:
    the detector finds both; each region's landmarks read the person nearest its centre, or,
    `one_person`, the same person in both (a second region on the first person)."""

    SIZE, FRONT, BEHIND = 100.0, np.array([100.0, 100.0]), np.array([120.0, 100.0])

    def __init__(self, one_person: bool = False) -> None:
        super().__init__()
        self.one_person = one_person

    def detect(self, image: np.ndarray) -> list[Roi]:
        return [Roi(self.FRONT.copy(), self.SIZE), Roi(self.BEHIND.copy(), self.SIZE)]

    def _person(self, image: np.ndarray, region: Roi) -> Person:
        behind = not self.one_person and np.linalg.norm(region.centre - self.BEHIND) < 5
        who = self.BEHIND if behind else self.FRONT
        spread = np.linspace(-30, 30, len(self.layout))  # a tall figure about its centre
        keypoints = np.stack([np.full(len(self.layout), who[0]), who[1] + spread, np.ones(len(self.layout))], 1)
        return Person(keypoints, 0.9 if behind else 1.0, Roi(who.copy(), self.SIZE))


def test_a_person_behind_another_is_kept_and_a_second_region_on_one_person_is_not() -> None:
    image = np.zeros((200, 240, 3), np.uint8)
    people = Tracker(OneBehindAnother(), max_people=4).step({"c": image})["c"]
    assert sorted(p.keypoints[0, 0] for p in people) == [100.0, 120.0]  # both, 20 px apart
    people = Tracker(OneBehindAnother(one_person=True), max_people=4).step({"c": image})["c"]
    assert len(people) == 1 and people[0].keypoints[0, 0] == 100.0


def test_the_tracker_drops_people_below_the_models_presence_threshold() -> None:
    image = fake_frames(1)[0].image
    assert len(Tracker(FakeDetector(presence=0.6)).step({"c": image})["c"]) == 1
    assert Tracker(FakeDetector(presence=0.6, min_presence=0.7)).step({"c": image})["c"] == []
    assert len(Tracker(FakeDetector(presence=0.6, min_presence=0.7), min_presence=0.5).step({"c": image})["c"]) == 1


def top_down_config(folder: Path, **keys) -> Path:
    """BlazePose's landmark network described as any regression model (topdown.py)."""
    path = folder / "model.json"
    path.write_text(json.dumps({"format": "mocap.edge-model/1", "onnx": str(LANDMARKS_ONNX), "layout": "blazepose33",
                                "input": [256, 256], "channels_first": False, "std": [255, 255, 255],
                                "decoder": "regression", "values_per_keypoint": 5, **keys}))
    return path


def test_the_top_down_models_min_presence_is_the_trackers_threshold(tmp_path: Path) -> None:
    assert ModelConfig.load(top_down_config(tmp_path)).min_presence == 0.3  # the documented default
    image = fake_frames(1)[0].image  # a red square: the landmark network's mean confidence is 0.15 on it

    def people(min_presence: float) -> list:
        config = ModelConfig.load(top_down_config(tmp_path, min_presence=min_presence))
        model = TopDownModel(config, people=FakeDetector())  # the fake finds the square
        assert model.min_presence == min_presence
        return Tracker(model).step({"c": image})["c"]

    assert len(people(0.0)) == 1
    assert people(1.0) == []


def test_a_configuration_path_opens_the_top_down_model(tmp_path: Path) -> None:
    model = open_detector(str(top_down_config(tmp_path, min_presence=0.2)))
    assert isinstance(model, TopDownModel) and model.min_presence == 0.2 and len(model.layout) == 33
    assert isinstance(open_detector(f"topdown:{top_down_config(tmp_path)}"), TopDownModel)
