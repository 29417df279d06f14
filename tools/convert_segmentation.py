"""Convert MediaPipe's person models (Apache-2.0) to the ONNX files that relightnet ships.

Not run by ``make``: the converted files in ``relightnet/weights/`` are what ships. This script
documents and reproduces them. It needs TensorFlow and tf2onnx, which the project does not
depend on, so run it in a throwaway environment:

    python3.11 -m venv /tmp/segconv && /tmp/segconv/bin/pip install tensorflow-cpu==2.21.0 \\
        tf2onnx==1.17.0 onnx onnxruntime scikit-image
    pip download mediapipe==0.10.21 --no-deps --only-binary=:all: --python-version 3.11 \\
        --platform manylinux_2_28_x86_64 -d /tmp/mp      # the wheel only; mediapipe is not installed
    /tmp/segconv/bin/python tools/convert_segmentation.py /tmp/mp/mediapipe-0.10.21-*.whl

What it does:

1. takes ``selfie_segmentation.tflite`` and ``pose_landmark_full.tflite`` out of the wheel;
2. converts each with tf2onnx (opset 17). The selfie model's last layer is MediaPipe's custom op
   ``Convolution2DTransposeBias`` (a 2x2, stride-2 transposed convolution plus bias); it is
   replaced by the standard ONNX ``ConvTranspose`` with the same weights;
3. runs the source ``.tflite`` models in the TF Lite interpreter and the ONNX files in ONNX Runtime
   on real photos (scikit-image's ``astronaut``, and ``chelsea`` as a photo without a person) and
   fails if they disagree;
4. writes the ONNX files to ``relightnet/weights/`` and the source models' outputs (and the
   inputs' hash) to ``tests/segment/reference_outputs.npz`` (the tests compare ONNX Runtime against
   them without TensorFlow), and prints the sha256 of every file for ``relightnet/weights/NOTICE``.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import sys
import zipfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SOURCES = {
    "person_selfie.onnx": "mediapipe/modules/selfie_segmentation/selfie_segmentation.tflite",
    "person_pose.onnx": "mediapipe/modules/pose_landmark/pose_landmark_full.tflite",
}
OPSET = 17
# Allowed |ONNX - TF Lite| <= atol + rtol * |TF Lite| per output: float32 rounding in another order.
# The pose model's mask logits (Identity_2) reach +-1700 far from the person's outline; they are
# compared as probabilities (after the sigmoid relightnet applies).
TOLERANCE = {"activation_10": (1e-3, 0.0), "Identity_2": (1e-2, 0.0)}
DEFAULT_TOLERANCE = (0.05, 1e-2)


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def sigmoid(x: np.ndarray) -> np.ndarray:
    return 0.5 * (1 + np.tanh(0.5 * x))


def real_inputs() -> np.ndarray:
    """(2, 256, 256, 3) uint8: scikit-image's astronaut (every other pixel) and a crop of chelsea (a cat)."""
    from skimage import data

    astronaut = data.astronaut()[::2, ::2]
    cat = data.chelsea()[22:278, 100:356]
    return np.stack([astronaut, cat]).astype(np.uint8)


def replace_transpose_bias(model):
    """Swap MediaPipe's ``Convolution2DTransposeBias`` (NHWC, weights OHWI) for ONNX ``ConvTranspose``."""
    import onnx
    from onnx import helper, numpy_helper

    g = model.graph
    inits = {i.name: i for i in g.initializer}
    for idx, node in enumerate(list(g.node)):
        if "Convolution2DTransposeBias" not in node.op_type:
            continue
        x, w_name, b_name = node.input
        w = numpy_helper.to_array(inits[w_name])  # (O, kH, kW, I)
        if w.shape[1:3] != (2, 2):
            raise SystemExit(f"{node.name}: expected a 2x2 kernel, got {w.shape}")
        b = numpy_helper.to_array(inits[b_name])
        pre = node.name + "_w"
        g.initializer.extend([numpy_helper.from_array(np.ascontiguousarray(w.transpose(3, 0, 1, 2)), pre),
                              numpy_helper.from_array(b.astype(np.float32), pre + "_b")])
        new = [
            helper.make_node("Transpose", [x], [pre + "_nchw"], perm=[0, 3, 1, 2]),
            helper.make_node("ConvTranspose", [pre + "_nchw", pre, pre + "_b"], [pre + "_y"],
                             kernel_shape=[2, 2], strides=[2, 2]),
            helper.make_node("Transpose", [pre + "_y"], list(node.output), perm=[0, 2, 3, 1]),
        ]
        g.node.remove(node)
        for k, n in enumerate(new):
            g.node.insert(idx + k, n)
    used = {i for n in g.node for i in n.input}
    for init in list(g.initializer):
        if init.name not in used:
            g.initializer.remove(init)
    for imp in list(model.opset_import):
        if imp.domain not in ("", "ai.onnx"):
            model.opset_import.remove(imp)
    onnx.checker.check_model(model)
    return model


def drop_noop_reshapes(model):
    """Remove Reshape nodes whose output has their input's (static) shape. tf2onnx's optimizer
    removes some of them and not others from one run to the next."""
    import onnx

    g = model.graph
    inferred = onnx.shape_inference.infer_shapes(model).graph
    shapes = {}
    for v in (*inferred.value_info, *inferred.input, *inferred.output):
        dims = v.type.tensor_type.shape.dim
        if all(d.HasField("dim_value") for d in dims):
            shapes[v.name] = tuple(d.dim_value for d in dims)
    outputs = {o.name for o in g.output}
    rename: dict[str, str] = {}
    for node in list(g.node):
        node.input[:] = [rename.get(i, i) for i in node.input]
        x, y = (node.input[0], node.output[0]) if node.op_type == "Reshape" else (None, None)
        if x is not None and y not in outputs and shapes.get(x) is not None and shapes.get(x) == shapes.get(y):
            rename[y] = x
            g.node.remove(node)
    return model


def canonical_names(model):
    """Rename nodes, tensors and weights by position and sort attributes: tf2onnx numbers names
    with a counter that keeps running across conversions, so without this the same model gives
    different bytes from run to run."""
    g = model.graph
    keep = {v.name for v in (*g.input, *g.output)}
    weights = {init.name for init in g.initializer}
    names: dict[str, str] = {}
    for node in g.node:  # weights numbered in the order the nodes use them (tf2onnx's order varies)
        for i in node.input:
            if i in weights and i not in names:
                names[i] = f"w{len(names)}"
    for k, node in enumerate(g.node):
        node.name = f"{node.op_type}_{k}"
        attrs = sorted(node.attribute, key=lambda a: a.name)  # tf2onnx's order follows a set
        del node.attribute[:]
        node.attribute.extend(attrs)
        for j, o in enumerate(node.output):
            if o not in keep:
                names.setdefault(o, f"t{k}_{j}")
    inits = sorted((i for i in g.initializer if i.name in names), key=lambda i: int(names[i.name][1:]))
    for init in inits:
        init.name = names[init.name]
    del g.initializer[:]
    g.initializer.extend(inits)
    for node in g.node:
        node.input[:] = [names.get(i, i) for i in node.input]
        node.output[:] = [names.get(o, o) for o in node.output]
    del g.value_info[:]
    return model


def run_tflite(path: Path, x: np.ndarray) -> dict[str, np.ndarray]:
    import tensorflow as tf

    it = tf.lite.Interpreter(model_path=str(path))
    it.allocate_tensors()
    outs: dict[str, list] = {}
    for img in x:
        it.set_tensor(it.get_input_details()[0]["index"], img[None].astype(np.float32) / 255)
        it.invoke()
        for d in it.get_output_details():
            outs.setdefault(d["name"], []).append(it.get_tensor(d["index"])[0].copy())
    return {k: np.stack(v) for k, v in outs.items()}


def run_onnx(data: bytes, x: np.ndarray) -> dict[str, np.ndarray]:
    import onnxruntime as ort

    s = ort.InferenceSession(data, providers=["CPUExecutionProvider"])
    outs: dict[str, list] = {}
    for img in x:
        res = s.run(None, {s.get_inputs()[0].name: img[None].astype(np.float32) / 255})
        for o, v in zip(s.get_outputs(), res, strict=True):
            outs.setdefault(o.name, []).append(v[0])
    return {k: np.stack(v) for k, v in outs.items()}


def main(argv=None) -> int:
    if os.environ.get("PYTHONHASHSEED") != "0":
        # tf2onnx's graph rewrites iterate over sets: the same seed gives the same bytes.
        os.execve(sys.executable, [sys.executable, *sys.argv], {**os.environ, "PYTHONHASHSEED": "0"})
    import tf2onnx

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("wheel", type=Path, help="mediapipe-0.10.21-*.whl")
    ap.add_argument("--weights", type=Path, default=ROOT / "relightnet" / "weights")
    ap.add_argument("--fixture", type=Path, default=ROOT / "tests" / "segment" / "reference_outputs.npz")
    ap.add_argument("--work", type=Path, default=Path("/tmp/relightnet_segconv"))
    args = ap.parse_args(argv)

    args.work.mkdir(parents=True, exist_ok=True)
    x = real_inputs()
    # The inputs are rebuilt by the tests from scikit-image (recorded: their hash).
    fixture = {"inputs_sha256": np.array(sha256(x.tobytes()))}
    with zipfile.ZipFile(args.wheel) as z:
        for out_name, member in SOURCES.items():
            src = args.work / Path(member).name
            src.write_bytes(z.read(member))
            print(f"source {member}  sha256 {sha256(src.read_bytes())}")
            model, _ = tf2onnx.convert.from_tflite(str(src), opset=OPSET)
            model = canonical_names(drop_noop_reshapes(replace_transpose_bias(model)))
            data = model.SerializeToString()
            ref, got = run_tflite(src, x), run_onnx(data, x)
            for k, v in ref.items():
                if k == "Identity_2":
                    err, v_cmp = np.abs(sigmoid(got[k]) - sigmoid(v)), sigmoid(v)
                else:
                    err, v_cmp = np.abs(got[k] - v), v
                atol, rtol = TOLERANCE.get(k, DEFAULT_TOLERANCE)
                print(f"  {out_name} {k} {tuple(v.shape[1:])}: max |onnx - tflite| = {err.max():.2e}, "
                      f"relative to |tflite| + 1: {(err / (np.abs(v_cmp) + 1)).max():.2e}")
                if (err > atol + rtol * np.abs(v_cmp)).any():
                    raise SystemExit(f"{out_name}: output {k} differs from the source model by {err.max()}")
                # Maps in float16 (the tests' tolerances allow it), the rest in float32.
                fixture[f"{Path(out_name).stem}.{k}"] = v.astype(np.float16 if v.ndim == 4 else np.float32)
            (args.weights / out_name).write_bytes(data)
            print(f"wrote {args.weights / out_name} ({len(data) / 1e6:.1f} MB)  sha256 {sha256(data)}")
    args.fixture.parent.mkdir(parents=True, exist_ok=True)
    # The 64x64x39 heatmaps are not used by relightnet: left out to keep the fixture small.
    np.savez_compressed(args.fixture, **{k: v for k, v in fixture.items() if not k.endswith("Identity_3")})
    print(f"wrote {args.fixture}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
