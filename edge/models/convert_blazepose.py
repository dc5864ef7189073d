"""Convert MediaPipe BlazePose (pose detector + full landmark model) to ONNX and validate it.

Runs in a throwaway venv, never the project's (TensorFlow is not a project dependency):

  python3.11 -m venv /tmp/convert-venv
  /tmp/convert-venv/bin/pip install tensorflow-cpu==2.15.1 tf2onnx==1.17.0 onnx==1.17.0 onnxruntime==1.20.1 \
      opencv-python-headless==4.10.0.84 numpy==1.26.4 protobuf==4.25.9 flatbuffers==25.12.19
  /tmp/convert-venv/bin/pip install --no-deps mediapipe==0.10.14 pose2sim==0.10.49
  /tmp/convert-venv/bin/python edge/models/convert_blazepose.py --out edge/models/blazepose \
      --fixtures edge/python/tests/data

mediapipe supplies the .tflite files, its LICENSE and its compiled-in graph configs; pose2sim
(--no-deps: only its demo videos are read) supplies real frames for the validation.
"""

import argparse
import glob
import hashlib
import importlib
import importlib.util
import math
import re
import shutil
import sys
import tempfile
import types
from pathlib import Path

import cv2
import numpy as np
import onnx
import onnxruntime as ort
import tensorflow as tf
import tf2onnx
from tensorflow.lite.python import schema_py_generated as schema
from tensorflow.lite.tools import flatbuffer_utils

MODELS = {"pose_detection": "modules/pose_detection", "pose_landmark_full": "modules/pose_landmark"}
# Outputs the edge reads: landmarks, pose flag, heatmap (refines the landmarks, as MediaPipe
# does), world landmarks — not the segmentation mask.
EDGE_OUTPUTS = {"pose_landmark_full": ["Identity", "Identity_1", "Identity_3", "Identity_4"]}
GRAPHS = ["PoseDetectionCpu", "PoseDetectionToRoi", "PoseLandmarkByRoiCpu",
          "TensorsToPoseLandmarksAndSegmentation", "PoseLandmarksToRoi"]
NO_DELEGATES = tf.lite.experimental.OpResolverType.BUILTIN_WITHOUT_DEFAULT_DELEGATES
VIDEOS = "Demo_SinglePerson/videos/cam0{}.mp4"


def package_dir(name: str) -> Path:
    return Path(importlib.util.find_spec(name).submodule_search_locations[0])


def tflite(path: Path, threads: int = 2, **kw) -> tf.lite.Interpreter:
    # XNNPACK (a default delegate) gives wrong DENSIFY outputs: always run the reference kernels.
    it = tf.lite.Interpreter(model_path=str(path), experimental_op_resolver_type=NO_DELEGATES, num_threads=threads,
                             **kw)
    it.allocate_tensors()
    return it


def run_tflite(it: tf.lite.Interpreter, x: np.ndarray) -> dict[str, np.ndarray]:
    it.set_tensor(it.get_input_details()[0]["index"], x)
    it.invoke()
    return {d["name"]: it.get_tensor(d["index"]).copy() for d in it.get_output_details()}


def bake_densify(src: Path, dst: Path) -> int:
    """Replaces each DENSIFY op (sparse weights, rejected by tf2onnx) by its output as a dense constant."""
    it = tflite(src, experimental_preserve_all_tensors=True)
    run_tflite(it, np.zeros(it.get_input_details()[0]["shape"], np.float32))
    model = flatbuffer_utils.read_model(str(src))
    assert len(model.subgraphs) == 1
    graph, kept = model.subgraphs[0], []
    for op in graph.operators:
        code = model.operatorCodes[op.opcodeIndex]
        if max(code.builtinCode, code.deprecatedBuiltinCode) != schema.BuiltinOperator.DENSIFY:
            kept.append(op)
            continue
        buffer = schema.BufferT()
        buffer.data = np.frombuffer(it.get_tensor(op.outputs[0]).tobytes(), np.uint8)
        model.buffers.append(buffer)
        for t in (op.inputs[0], op.outputs[0]):  # the orphaned sparse input becomes dense too (same shape)
            graph.tensors[t].buffer, graph.tensors[t].sparsity = len(model.buffers) - 1, None
    baked = len(graph.operators) - len(kept)
    graph.operators = kept
    flatbuffer_utils.write_model(model, str(dst))
    return baked


def canonical_names(path: Path) -> None:
    """tf2onnx numbers the names it makes in a run-dependent order: rename them so reruns give identical files.

    Constants are named by their content; the "__<n>" suffixes of other names are renumbered in node order.
    """
    model = onnx.load(str(path))
    graph, rename, unique, numbers = model.graph, {}, {}, {}
    for init in graph.initializer:
        content = onnx.TensorProto()
        content.CopyFrom(init)
        content.name = ""
        rename[init.name] = content.name = "const_" + hashlib.sha256(content.SerializeToString()).hexdigest()[:16]
        unique[content.name] = content
    for node in graph.node:
        for name in (node.name, *node.output):
            for n in re.findall(r"__(\d+)", name):
                numbers.setdefault(n, str(len(numbers)))

    def new(name: str) -> str:
        return rename.get(name) or re.sub(r"__(\d+)", lambda m: "__" + numbers.get(m[1], m[1]), name)

    for node in graph.node:
        node.name = new(node.name)
        node.input[:] = [new(i) for i in node.input]
        node.output[:] = [new(o) for o in node.output]
    for info in graph.value_info:
        info.name = new(info.name)
    del graph.initializer[:]
    graph.initializer.extend(unique[k] for k in sorted(unique))
    onnx.save(model, str(path))


def edge_variant(path: Path, keep: list[str]) -> int:
    """Only the outputs the edge reads (`keep`), the nodes that feed them, and a symbolic batch
    dimension so one inference takes the crops of several cameras. The landmark model's
    segmentation branch is two thirds of its time (14.4 -> 4.9 ms per crop, 2 threads); the
    outputs kept are unchanged. Returns the number of nodes dropped."""
    model = onnx.load(str(path))
    graph = model.graph
    outputs = [o for o in graph.output if o.name in keep]
    needed, nodes = set(keep), []
    for node in reversed(graph.node):
        if any(o in needed for o in node.output):
            nodes.append(node)
            needed.update(node.input)
    dropped = len(graph.node) - len(nodes)
    inits = [i for i in graph.initializer if i.name in needed]
    for tensor in (*graph.input, *outputs):
        tensor.type.tensor_type.shape.dim[0].dim_param = "batch"
    for node in nodes:  # reshapes to a fixed batch of 1 -> the input's batch
        if node.op_type == "Reshape":
            shape = next(i for i in inits if i.name == node.input[1])
            value = onnx.numpy_helper.to_array(shape).copy()
            if value[0] == 1:
                value[0] = 0 if -1 in value else -1  # 0: copy the input's dimension
                shape.CopyFrom(onnx.numpy_helper.from_array(value.astype(np.int64), shape.name))
    del graph.output[:], graph.node[:], graph.initializer[:], graph.value_info[:]
    graph.output.extend(outputs)
    graph.node.extend(reversed(nodes))
    graph.initializer.extend(inits)
    onnx.checker.check_model(model)
    onnx.save(model, str(path))
    return dropped


def dump_graph_configs(mp_dir: Path, out: Path) -> None:
    """Writes the pose subgraph configs compiled into the wheel's _framework_bindings.so as text."""
    sys.modules["mediapipe"] = types.ModuleType("mediapipe")  # the *_pb2 modules without mediapipe's imports
    sys.modules["mediapipe"].__path__ = [str(mp_dir)]
    from google.protobuf import text_format
    from mediapipe.framework import calculator_pb2
    for f in glob.glob(f"{mp_dir}/calculators/**/*_pb2.py", recursive=True):  # registers the options extensions
        importlib.import_module("mediapipe." + str(Path(f).relative_to(mp_dir))[:-3].replace("/", "."))
    blob = next(mp_dir.glob("python/_framework_bindings*.so")).read_bytes()
    texts = []
    for name in GRAPHS:
        tail = b"\xa2\x01" + bytes([len(name)]) + name.encode()  # field 20 (type) ends the message
        end = blob.index(tail) + len(tail)
        start = blob.rindex(b"\0" * 8, 0, end) + 8
        config = calculator_pb2.CalculatorGraphConfig()
        while True:
            try:
                config.ParseFromString(blob[start:end])
                if config.type == name:
                    break
            except Exception:  # noqa: BLE001 - not yet at the message start
                pass
            start += 1
        texts.append(f"# ---- {name}\n" + text_format.MessageToString(config))
    out.write_text("# Extracted from mediapipe==0.10.14 (_framework_bindings.so) by convert_blazepose.py\n"
                   + "\n".join(texts))


def anchors() -> np.ndarray:
    """(2254, 2) anchor centres (x, y) in [0, 1]: SsdAnchorsCalculator with PoseDetectionCpu's options."""
    out = []
    for stride, per_cell in ((8, 2), (16, 2), (32, 6)):  # the three stride-32 layers share one grid
        n = 224 // stride
        y, x = np.mgrid[0:n, 0:n]
        centres = np.stack([(x + 0.5) / n, (y + 0.5) / n], -1).reshape(-1, 1, 2)
        out.append(np.repeat(centres, per_cell, axis=1).reshape(-1, 2))
    return np.concatenate(out)


def letterbox(rgb: np.ndarray, size: int = 224) -> tuple[np.ndarray, float, np.ndarray]:
    scale = size / max(rgb.shape[:2])
    h, w = round(rgb.shape[0] * scale), round(rgb.shape[1] * scale)
    pad = np.array([(size - w) // 2, (size - h) // 2])
    out = np.zeros((size, size, 3), np.uint8)
    out[pad[1]:pad[1] + h, pad[0]:pad[0] + w] = cv2.resize(rgb, (w, h), interpolation=cv2.INTER_LINEAR)
    return out, scale, pad


def crop_person(rgb: np.ndarray, det: dict[str, np.ndarray], scale: float, pad: np.ndarray) -> np.ndarray:
    """256x256 crop around the best detection, as PoseDetectionToRoi (keypoints 0, 1; x1.25; rotation)."""
    i = int(np.argmax(det["Identity_1"][0, :, 0]))
    kp = det["Identity"][0, i, 4:8].reshape(2, 2) + anchors()[i] * 224  # letterboxed pixels
    (x0, y0), (x1, y1) = (kp - pad) / scale  # frame pixels
    size = 2 * math.hypot(x1 - x0, y1 - y0) * 1.25
    rot = math.pi / 2 - math.atan2(-(y1 - y0), x1 - x0)  # clockwise, y down
    c, s = math.cos(rot) * size / 256, math.sin(rot) * size / 256
    dst_to_src = np.array([[c, -s, x0 - 128 * (c - s)], [s, c, y0 - 128 * (s + c)]])
    return cv2.warpAffine(rgb, dst_to_src, (256, 256), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REPLICATE)


def real_inputs(p2s_dir: Path) -> list[tuple[np.ndarray, np.ndarray, float, np.ndarray]]:
    """(frame RGB, 224 letterboxed RGB, scale, pad) for frames 0 and 50 of the four demo cameras."""
    out = []
    for cam in range(1, 5):
        video = cv2.VideoCapture(str(p2s_dir / VIDEOS.format(cam)))
        for index in (0, 50):
            video.set(cv2.CAP_PROP_POS_FRAMES, index)
            ok, bgr = video.read()
            assert ok, (cam, index)
            rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
            out.append((rgb, *letterbox(rgb)))
    return out


def sigmoid(v: np.ndarray) -> np.ndarray:
    return 1 / (1 + np.exp(-np.clip(v.astype(np.float64), -100, 100)))


def diff_report(name: str, ref: list[dict], got: list[dict]) -> None:
    """Max |TFLite - ONNX| per output (and relative to max |TFLite|; after a sigmoid for logit outputs)."""
    logits = {"Identity_1"} if name == "detector" else {"Identity_2", "Identity_3"}
    for key in [k for k in ref[0] if k in got[0]]:  # the edge variant drops some outputs
        d = max(np.abs(r[key] - g[key]).max() for r, g in zip(ref, got))
        line = f"  {name} {key:10s} {str(ref[0][key].shape):16s} {d:.3g} (rel {d / np.abs(ref[0][key]).max():.1g})"
        if key in logits:
            line += f", sigmoid {max(np.abs(sigmoid(r[key]) - sigmoid(g[key])).max() for r, g in zip(ref, got)):.2g}"
        print(line)
        if ref[0][key].shape[-1] == 195:  # 39 x (x, y, z [px of 256], visibility, presence [logits])
            for part, cols in (("x,y,z px", slice(0, 3)), ("vis,pres logits", slice(3, 5))):
                d = max(np.abs(r[key] - g[key]).reshape(39, 5)[:, cols].max() for r, g in zip(ref, got))
                print(f"    {part} {d:.3g}")


def convert_models(mp_dir: Path, out: Path) -> tuple[dict, dict]:
    """Each model converted to ONNX in `out` (DENSIFY baked, canonical names, the edge
    variant), with its hashes printed: (ONNX sessions, TFLite interpreters) by name."""
    sessions, interpreters = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, sub in MODELS.items():
            src, baked, dst = mp_dir / sub / f"{name}.tflite", Path(tmp) / f"{name}.tflite", out / f"{name}.onnx"
            print(f"{name}: sha256 tflite {hashlib.sha256(src.read_bytes()).hexdigest()}")
            print(f"  baked {bake_densify(src, baked)} DENSIFY ops")
            tf2onnx.convert.from_tflite(str(baked), opset=13, output_path=str(dst))
            canonical_names(dst)
            if name in EDGE_OUTPUTS:
                print(f"  edge variant: {edge_variant(dst, EDGE_OUTPUTS[name])} nodes dropped, batch dimension symbolic")
            print(f"  sha256 onnx   {hashlib.sha256(dst.read_bytes()).hexdigest()}")
            interpreters[name] = tflite(src)
            if name == "pose_detection":  # the baked flatbuffer computes what the original does (1 thread: exactly)
                x = np.random.default_rng(0).uniform(-1, 1, (1, 224, 224, 3)).astype(np.float32)
                d = max(np.abs(a - b).max() for a, b in zip(run_tflite(tflite(baked, 1), x).values(),
                                                             run_tflite(tflite(src, 1), x).values()))
                print(f"  baked vs original TFLite (1 thread) max diff {d}")
            opts = ort.SessionOptions()
            opts.intra_op_num_threads = 2
            sessions[name] = ort.InferenceSession(str(dst), opts, providers=["CPUExecutionProvider"])
    return sessions, interpreters


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="folder for the .onnx files, LICENSE, graph configs")
    ap.add_argument("--fixtures", type=Path, help="folder for the test fixtures (inputs as PNG, TFLite outputs)")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    mp_dir = package_dir("mediapipe")
    shutil.copy(next(mp_dir.parent.glob("mediapipe-0.10.14.dist-info")) / "LICENSE", args.out / "LICENSE")
    dump_graph_configs(mp_dir, args.out / "mediapipe_graphs.pbtxt")

    sessions, interpreters = convert_models(mp_dir, args.out)

    def both(name: str, inputs: list[np.ndarray]) -> tuple[list[dict], list[dict]]:
        sess = sessions[name]
        ref = [run_tflite(interpreters[name], x) for x in inputs]
        got = [dict(zip([o.name for o in sess.get_outputs()], sess.run(None, {sess.get_inputs()[0].name: x})))
               for x in inputs]
        return ref, got

    frames = real_inputs(package_dir("Pose2Sim"))
    det_in = [(lb[None] / 127.5 - 1).astype(np.float32) for _, lb, _, _ in frames]  # [-1, 1]
    det_ref, det_got = both("pose_detection", det_in)
    crops = [crop_person(rgb, d, s, p) for (rgb, _, s, p), d in zip(frames, det_ref)]
    lm_in = [(c[None] / 255).astype(np.float32) for c in crops]  # [0, 1]
    lm_ref, lm_got = both("pose_landmark_full", lm_in)
    print(f"real frames ({len(frames)}): max |TFLite - ONNX|")
    print("  best detection score", [round(float(sigmoid(d["Identity_1"]).max()), 3) for d in det_ref])
    print("  pose flag of the crops", [round(float(r["Identity_1"][0, 0]), 3) for r in lm_ref])
    diff_report("detector", det_ref, det_got)
    diff_report("landmark", lm_ref, lm_got)
    rng = np.random.default_rng(1)
    print("random inputs (4 per model, uniform over the input range):")
    diff_report("detector", *both("pose_detection", [rng.uniform(-1, 1, (1, 224, 224, 3)).astype(np.float32)
                                                      for _ in range(4)]))
    diff_report("landmark", *both("pose_landmark_full", [rng.uniform(0, 1, (1, 256, 256, 3)).astype(np.float32)
                                                          for _ in range(4)]))
    if args.fixtures:  # camera 1, frame 50
        args.fixtures.mkdir(parents=True, exist_ok=True)
        cv2.imwrite(str(args.fixtures / "detector_input_224.png"), cv2.cvtColor(frames[1][1], cv2.COLOR_RGB2BGR))
        np.savez_compressed(args.fixtures / "detector_tflite.npz", **det_ref[1])
        cv2.imwrite(str(args.fixtures / "landmark_input_256.png"), cv2.cvtColor(crops[1], cv2.COLOR_RGB2BGR))
        np.savez_compressed(args.fixtures / "landmark_tflite.npz",
                            **{k: v for k, v in lm_ref[1].items() if k in ("Identity", "Identity_1", "Identity_4")})


if __name__ == "__main__":
    main()
