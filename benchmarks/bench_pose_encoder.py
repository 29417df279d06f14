"""The pose encoder (``relightnet.model.pose_encoder``, taps at strides 2 to 32) in torch vs ONNX Runtime.

Run: ``.venv/bin/python benchmarks/bench_pose_encoder.py [--batch 8] [--size 256] [--repeat 7]``.
Forward time (median, no grad) of: the torch interpreter's taps (eager, NCHW and channels_last);
ONNX Runtime running the shipped file's full graph (every head; its fixed (1, 256, 256, 1) mask
reshape loosened to the batch); ONNX Runtime running the same file cut to the five taps; and ONNX
Runtime running the taps as torch exports them (``torch.onnx.export(dynamo=True)``). 1 and 2 threads.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import median_ms, table  # noqa: E402

from relightnet.model.onnx_torch import POSE_TAPS, GraphModule, cut_to_outputs, load_onnx, pose_encoder  # noqa: E402

OUTPUTS = ["Identity", "Identity_1", "Identity_2", "Identity_3", "Identity_4"]


def _cpu() -> str:
    for line in Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("model name"):
            return line.split(":", 1)[1].strip()
    return platform.processor()


def ort_model(outputs: list[str]) -> bytes:
    """The shipped graph with a free batch (and H, W), cut to ``outputs``."""
    import onnx

    m = onnx.ModelProto.FromString(load_onnx().SerializeToString())  # onnx's message, to mix in its tensors
    for dim, name in zip(m.graph.input[0].type.tensor_type.shape.dim, "BHW", strict=False):
        dim.dim_param = name
    for t in m.graph.initializer:  # Identity_2's Reshape: (1, 256, 256, 1) -> (-1, 256, 256, 1)
        if t.name == "w200":
            t.CopyFrom(onnx.numpy_helper.from_array(np.array([-1, 256, 256, 1], np.int64), "w200"))
    cut_to_outputs(m, outputs)
    return m.SerializeToString()


def exported_encoder(path: Path) -> Path:
    """The torch interpreter's taps exported by ``torch.onnx.export(dynamo=True)``, dynamic batch and size."""
    import logging
    import warnings

    for name in ("torch.onnx", "onnx_ir", "onnxscript"):
        logging.getLogger(name).setLevel(logging.ERROR)
    b = torch.export.Dim("batch", min=1, max=1024)
    h, w = torch.export.Dim("h32", min=1, max=256), torch.export.Dim("w32", min=1, max=256)
    with torch.no_grad(), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prog = torch.onnx.export(pose_encoder().eval(), (torch.rand(2, 3, 64, 64),), dynamo=True, verbose=False,
                                 input_names=["image"], dynamic_shapes={"x": {0: b, 2: 32 * h, 3: 32 * w}})
    path.write_bytes(prog.model_proto.SerializeToString())
    return path


def ort_session(model, threads: int):
    import onnxruntime as ort

    opts = ort.SessionOptions()
    opts.intra_op_num_threads, opts.inter_op_num_threads, opts.log_severity_level = threads, 1, 3
    return ort.InferenceSession(model if isinstance(model, bytes) else str(model), opts,
                                providers=["CPUExecutionProvider"])


def ort_ms(sess, feeds: dict, repeat: int) -> float:
    """Median ms of one ONNX Runtime run."""
    return median_ms(lambda: sess.run(None, feeds), repeat)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    x = torch.rand(args.batch, 3, args.size, args.size)
    nhwc = {"input_1": x.permute(0, 2, 3, 1).contiguous().numpy()}
    enc = pose_encoder().eval()
    enc_cl = pose_encoder().eval().to(memory_format=torch.channels_last)
    x_cl = x.contiguous(memory_format=torch.channels_last)
    taps = [t.name for t in POSE_TAPS]
    with tempfile.TemporaryDirectory() as tmp:
        exported = exported_encoder(Path(tmp) / "enc.onnx")
        rows = []
        for threads in (1, 2):
            torch.set_num_threads(threads)
            with torch.no_grad():
                eager = median_ms(lambda: enc(x), args.repeat)
                eager_cl = median_ms(lambda: enc_cl(x_cl), args.repeat)
            feeds = [(ort_session(ort_model(OUTPUTS), threads), nhwc), (ort_session(ort_model(taps), threads), nhwc),
                     (ort_session(exported, threads), {"image": x.numpy()})]
            rows.append([threads, eager, eager_cl] + [ort_ms(s, f, args.repeat) for s, f in feeds])
    n_enc = sum(p.numel() for p in enc.parameters())
    n_full = sum(p.numel() for p in GraphModule(load_onnx(), OUTPUTS).parameters())
    print(f"CPU: {_cpu()}; torch {torch.__version__}; B = {args.batch}, {args.size}²; "
          f"median of {args.repeat}; parameters: encoder {n_enc:,}, full graph {n_full:,}\n")
    print(table(["threads", "torch eager taps ms", "torch eager taps ms (channels_last)", "ORT full graph ms",
                 "ORT taps ms (file cut)", "ORT taps ms (torch export)"], rows))


if __name__ == "__main__":
    main()
