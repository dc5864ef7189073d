"""The BlazePose ONNX files (edge/models/blazepose) as committed: the files the README names, with the
inputs and outputs it documents, reproducing MediaPipe's TFLite outputs on real frames. The fixtures in
data/ (inputs as PNG, TFLite outputs as .npz) come from edge/models/convert_blazepose.py."""

import hashlib
import re
from pathlib import Path

import numpy as np
import onnxruntime as ort
import pytest
from PIL import Image

MODELS = Path(__file__).resolve().parents[2] / "models" / "blazepose"
DATA = Path(__file__).parent / "data"
# Above the largest TFLite - ONNX differences of the conversion's validation (README, "Validation"):
# real frames / random inputs.
PX_TOL = 5e-3  # coordinates, pixels of the model input (1.3e-3 / 3.2e-4 detector, 1.8e-3 / 4.3e-3 landmarks)
LOGIT_TOL = 2e-3  # scores, visibility and presence logits (4.3e-4 / 3.5e-4, 1.1e-4 / 1.3e-3)
FLAG_TOL = 1e-5  # pose flag, a probability (6e-7 / 4e-8)
METRE_TOL = 1e-4  # world landmarks (4.8e-6 / 3.0e-5 m)

IO = {
    "pose_detection": ({"input_1": [1, 224, 224, 3]}, {"Identity": [1, 2254, 12], "Identity_1": [1, 2254, 1]}),
    # The edge variant: no segmentation output, a symbolic batch (convert_blazepose.edge_variant).
    "pose_landmark_full": ({"input_1": ["batch", 256, 256, 3]},
                           {"Identity": ["batch", 195], "Identity_1": ["batch", 1],
                            "Identity_3": ["batch", 64, 64, 39], "Identity_4": ["batch", 117]}),
}


def session(name: str) -> ort.InferenceSession:
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    return ort.InferenceSession(str(MODELS / f"{name}.onnx"), options, providers=["CPUExecutionProvider"])


def run(name: str, x: np.ndarray) -> dict[str, np.ndarray]:
    sess = session(name)
    return dict(zip([o.name for o in sess.get_outputs()], sess.run(None, {"input_1": x})))


def rgb(png: str) -> np.ndarray:
    return np.asarray(Image.open(DATA / png).convert("RGB"), np.float32)[None]


@pytest.mark.parametrize("name", IO)
def test_file_is_the_one_the_readme_describes(name):
    readme = (MODELS / "README.md").read_text()
    documented = re.search(rf"`{name}\.onnx`\s*\|\s*`([0-9a-f]{{64}})`", readme)
    assert documented, f"no SHA-256 for {name}.onnx in the README"
    assert hashlib.sha256((MODELS / f"{name}.onnx").read_bytes()).hexdigest() == documented[1]


@pytest.mark.parametrize("name", IO)
def test_inputs_and_outputs(name):
    sess = session(name)
    inputs, outputs = IO[name]
    assert {i.name: i.shape for i in sess.get_inputs()} == inputs
    assert {o.name: o.shape for o in sess.get_outputs()} == outputs
    assert all(t.type == "tensor(float)" for t in sess.get_inputs() + sess.get_outputs())


def test_detector_reproduces_tflite_on_a_real_frame():
    expected = np.load(DATA / "detector_tflite.npz")
    got = run("pose_detection", rgb("detector_input_224.png") / 127.5 - 1)  # [-1, 1]
    np.testing.assert_allclose(got["Identity"], expected["Identity"], rtol=0, atol=PX_TOL)
    np.testing.assert_allclose(got["Identity_1"], expected["Identity_1"], rtol=0, atol=LOGIT_TOL)
    assert got["Identity_1"].max() > 0  # the person is found: score sigmoid(logit) > 0.5


def test_landmarks_reproduce_tflite_on_a_real_crop():
    expected = np.load(DATA / "landmark_tflite.npz")
    got = run("pose_landmark_full", rgb("landmark_input_256.png") / 255)  # [0, 1]
    lm, ref = got["Identity"].reshape(39, 5), expected["Identity"].reshape(39, 5)
    np.testing.assert_allclose(lm[:, :3], ref[:, :3], rtol=0, atol=PX_TOL)  # x, y, z
    np.testing.assert_allclose(lm[:, 3:], ref[:, 3:], rtol=0, atol=LOGIT_TOL)  # visibility, presence
    np.testing.assert_allclose(got["Identity_1"], expected["Identity_1"], rtol=0, atol=FLAG_TOL)
    np.testing.assert_allclose(got["Identity_4"], expected["Identity_4"], rtol=0, atol=METRE_TOL)
    assert got["Identity_1"][0, 0] > 0.5  # pose flag: already a probability
    assert (0 <= lm[:33, :2]).all() and (lm[:33, :2] < 256).all()  # the whole person is in the crop
