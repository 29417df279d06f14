"""ONNX serving speed and int8 quality: torch eager vs ONNX Runtime fp32 vs ONNX Runtime int8.

Run: ``.venv/bin/python benchmarks/bench_onnx.py`` (the shipped model with EMA smoothing in the
graph; 2 threads; B = 1). int8 quality: relit RMSE (each test item relit with the next item's
light) of the int8 model relative to the fp32 one, on generated test-split samples.
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


def main() -> None:
    torch.set_num_threads(2)
    net = load_model()
    tmp = Path(tempfile.mkdtemp())
    fp32 = export_onnx(net, tmp / "m.onnx", smoothing="ema")
    int8 = quantize_int8(fp32, tmp / "m_int8.onnx", mode="static")
    dyn = quantize_int8(fp32, tmp / "m_int8_dynamic.onnx", mode="dynamic")
    sess = {"fp32": OnnxRelighter(fp32, threads=2), "int8": OnnxRelighter(int8, threads=2),
            "int8 dynamic": OnnxRelighter(dyn, threads=2)}
    rows = []
    for size in (256, 512):
        img = np.random.default_rng(0).random((1, 3, size, size), dtype=np.float32)
        mask = np.ones((1, 1, size, size), np.float32)
        x = normalize_input(torch.from_numpy(img), torch.from_numpy(mask)).contiguous(memory_format=torch.channels_last)
        m = net.to(memory_format=torch.channels_last)
        with torch.no_grad():
            eager = median_ms(lambda m=m, x=x: m(x), repeat=5)
        times = {k: median_ms(lambda r=r, img=img, mask=mask: r.step(img, mask), repeat=5) for k, r in sess.items()}
        rows.append([f"{size}²", eager, times["fp32"], times["int8"], times["int8 dynamic"], eager / times["fp32"],
                     eager / times["int8"]])
    from relightnet.body import AnnyBody
    from relightnet.data import SynthConfig, generate_sample

    body = AnnyBody()
    samples = [generate_sample(SynthConfig(res=128, n_dirs=64), "test", i, body=body).arrays for i in range(12)]
    q = {k: relit_rmse(r, samples) for k, r in sess.items()}
    print(table(["size", "torch eager ms (channels_last)", "ORT fp32 ms", "ORT int8 static ms", "ORT int8 dynamic ms",
                 "eager/fp32", "eager/int8 static"], rows))
    print()
    print(table(["model", "relit RMSE (12 test samples, 128²)", "vs fp32"],
                [["ORT fp32", q["fp32"], 1.0], ["ORT int8 static (QDQ)", q["int8"], q["int8"] / q["fp32"]],
                 ["ORT int8 dynamic", q["int8 dynamic"], q["int8 dynamic"] / q["fp32"]]]))
    print(f"\nfile sizes: fp32 {fp32.stat().st_size / 1e6:.1f} MB, int8 static {int8.stat().st_size / 1e6:.1f} MB, "
          f"int8 dynamic {dyn.stat().st_size / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
