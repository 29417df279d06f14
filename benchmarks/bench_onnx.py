"""ONNX serving speed and int8 quality: torch eager vs ONNX Runtime fp32 vs ONNX Runtime int8.

Run: ``.venv/bin/python benchmarks/bench_onnx.py [--checkpoint C]`` (default: the shipped model,
with its default smoothing in the graph; 2 threads; B = 1). int8 quality: relit RMSE (each test
item relit with the next item's light) of the int8 models relative to the fp32 one, on 48 generated
test-split samples; static int8 with 7-bit weights (the default) and 8-bit weights (for CPUs with
VNNI/AMX), both with the default layers kept in float (``INT8_KEEP_FLOAT``), and static int8 of every
layer (``keep_float=()``, the former default).
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import median_ms, table  # noqa: E402

from relightnet.model import load_model, normalize_input, shading_map  # noqa: E402
from relightnet.model.onnx_export import export_onnx  # noqa: E402
from relightnet.model.onnx_serving import OnnxRelighter, quantize_int8  # noqa: E402


def relit_rmse(r: OnnxRelighter, samples) -> float:
    errs = []
    for i, a in enumerate(samples):
        nxt = torch.from_numpy(samples[(i + 1) % len(samples)]["light"])
        img = torch.from_numpy(a["image_srgb"]).permute(2, 0, 1)[None].float().numpy() / 255
        m = a["mask"][None, None].astype(np.float32)
        r.reset()
        out = r.step(img.astype(np.float32), m)
        pred = torch.from_numpy(out["albedo"]) * shading_map(torch.from_numpy(out["transport"]), nxt)
        gt = torch.from_numpy(a["albedo"]).permute(2, 0, 1)[None] * shading_map(
            torch.from_numpy(a["transport"]).permute(2, 0, 1)[None], nxt)
        mk = torch.from_numpy(m)
        errs.append(float((((pred - gt) ** 2) * mk).sum() / (mk.sum() * 3)) ** 0.5)
    return float(np.mean(errs))


def conv_share_ms(path: Path, img: np.ndarray, mask: np.ndarray, runs: int = 5) -> tuple[float, float]:
    """(convolution kernels, whole graph) ms per frame from ONNX Runtime's profiler (2 threads)."""
    import json

    import onnxruntime as ort

    opts = ort.SessionOptions()
    opts.intra_op_num_threads = 2
    opts.enable_profiling = True
    opts.profile_file_prefix = str(path.with_suffix(""))
    sess = ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"])
    r = OnnxRelighter(path, threads=2)
    feeds = {"image": img, "mask": mask, "light_state": np.zeros((1, r.state_size, r.n_coeffs, 3), np.float32),
             "is_first": np.ones((1,), np.bool_)}
    sess.run(None, feeds)  # warm-up (excluded below by its run index)
    for _ in range(runs):
        sess.run(None, feeds)
    events = json.loads(Path(sess.end_profiling()).read_text())
    runs_ev = [e for e in events if e.get("name") == "model_run"][1:]
    nodes = [e for e in events if e.get("cat") == "Node" and e["name"].endswith("_kernel_time")]
    t_first = runs_ev[0]["ts"]
    conv = sum(e["dur"] for e in nodes if e["ts"] >= t_first and e["args"].get("op_name") in _CONV_OPS)
    total = sum(e["dur"] for e in runs_ev)
    return conv / 1e3 / len(runs_ev), total / 1e3 / len(runs_ev)


_CONV_OPS = {"Conv", "QLinearConv", "ConvInteger", "FusedConv", "NhwcFusedConv"}


def main() -> None:
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("--checkpoint", default=None, help="model (default: the shipped one)")
    args = ap.parse_args()
    torch.set_num_threads(2)
    net = load_model(args.checkpoint)
    tmp = Path(tempfile.mkdtemp())
    fp32 = export_onnx(net, tmp / "m.onnx", smoothing="pooled" if net.solves else "ema")
    int8 = quantize_int8(fp32, tmp / "m_int8.onnx", mode="static")
    int8w8 = quantize_int8(fp32, tmp / "m_int8_w8.onnx", mode="static", reduce_range=False)
    every = quantize_int8(fp32, tmp / "m_int8_every.onnx", mode="static", keep_float=())
    dyn = quantize_int8(fp32, tmp / "m_int8_dynamic.onnx", mode="dynamic")
    sess = {"fp32": OnnxRelighter(fp32, threads=2), "int8": OnnxRelighter(int8, threads=2),
            "int8 8-bit": OnnxRelighter(int8w8, threads=2), "int8 dynamic": OnnxRelighter(dyn, threads=2),
            "int8 every layer": OnnxRelighter(every, threads=2)}
    rows = []
    for size in (256, 512):
        img = np.random.default_rng(0).random((1, 3, size, size), dtype=np.float32)
        mask = np.ones((1, 1, size, size), np.float32)
        x = normalize_input(torch.from_numpy(img), torch.from_numpy(mask)).contiguous(memory_format=torch.channels_last)
        m = net.to(memory_format=torch.channels_last)
        with torch.no_grad():
            eager = median_ms(lambda m=m, x=x: m(x), repeat=7)
        times = {k: median_ms(lambda r=r, img=img, mask=mask: r.step(img, mask), repeat=7) for k, r in sess.items()}
        rows.append([f"{size}²", eager, times["fp32"], times["int8"], times["int8 8-bit"], times["int8 every layer"],
                     times["int8 dynamic"], eager / times["fp32"], eager / times["int8"], eager / times["int8 8-bit"],
                     eager / times["int8 every layer"]])
    from relightnet.body import AnnyBody
    from relightnet.data import SynthConfig, generate_sample

    body = AnnyBody()
    samples = [generate_sample(SynthConfig(res=128, n_dirs=64), "test", i, body=body).arrays for i in range(48)]
    q = {k: relit_rmse(r, samples) for k, r in sess.items()}
    img = np.random.default_rng(0).random((1, 3, 256, 256), dtype=np.float32)
    ones = np.ones((1, 1, 256, 256), np.float32)
    share = {k: conv_share_ms(p, img, ones) for k, p in (("fp32", fp32), ("int8", int8), ("int8 8-bit", int8w8),
                                                          ("int8 every layer", every))}
    print(table(["size", "torch eager ms (channels_last)", "ORT fp32 ms", "ORT int8 static ms", "ORT int8 8-bit ms",
                 "ORT int8 every layer ms", "ORT int8 dynamic ms", "eager/fp32", "eager/int8 static",
                 "eager/int8 8-bit", "eager/int8 every layer"], rows))
    print()
    print(table(["model", f"relit RMSE ({len(samples)} test samples, 128²)", "vs fp32"],
                [["ORT fp32", q["fp32"], 1.0],
                 ["ORT int8 static (QDQ, 7-bit weights)", q["int8"], q["int8"] / q["fp32"]],
                 ["ORT int8 static (QDQ, 8-bit weights)", q["int8 8-bit"], q["int8 8-bit"] / q["fp32"]],
                 ["ORT int8 static, every layer (7-bit)", q["int8 every layer"], q["int8 every layer"] / q["fp32"]],
                 ["ORT int8 dynamic", q["int8 dynamic"], q["int8 dynamic"] / q["fp32"]]]))
    print()
    print(table(["256², ORT profiler", "convolution kernels ms", "whole graph ms", "convolutions / eager 256²"],
                [[k, c, t, c / rows[0][1]] for k, (c, t) in share.items()]))
    print(f"\nfile sizes: fp32 {fp32.stat().st_size / 1e6:.1f} MB, int8 static {int8.stat().st_size / 1e6:.1f} MB, "
          f"int8 dynamic {dyn.stat().st_size / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
