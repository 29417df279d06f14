"""Temporal light smoothing: quality and cost of every method on synthetic light sequences.

Run: ``OMP_NUM_THREADS=2 .venv/bin/python benchmarks/bench_temporal.py`` (2 threads). Prints two markdown tables.

Data: ``--seqs`` sequences of T = 300 frames (30 fps). Each is a preset light turning
about the up axis (an angle ``a sin(2π f t + φ)``, peak speed up to ~60°/s) that
switches at a random frame in [120, 180] to another preset (also turning): the step.
Gaussian noise of 10 % of the frame's RMS coefficient is added to every coefficient,
and 4 % of the frames (never within 3 frames of the switch) get a spike: a random
light of half the true light's norm (about 5× the noise's light distance).

Columns (medians over sequences):
- jitter: mean light distance of the second difference (the irradiance L2 over the
  sphere, :func:`relightnet.temporal.jitter`), frames within 10 of the switch left
  out; change vs the raw input (goal −80 %).
- error: mean light distance to the truth, as a ratio to the raw input's.
- lag: frames after the switch until 90 % of it is reached (goal ≤ 2).
- recall / precision of the injected spikes (goal recall ≥ 90 %); "—" where the
  method has no outlier detection.
- µs/frame: wall time per frame for one sequence (causal filters: one ``forward``
  per frame through :func:`run_causal`, i.e. including the Python call per frame).

The second table compares our loop-free forms with SciPy (the peer) on the same
(T, 27) coefficient arrays: Savitzky–Golay vs ``scipy.signal.savgol_filter``
(mode "interp") and the EMA matmul vs ``scipy.signal.lfilter``. The third times one
causal step exported to ONNX (``torch.onnx.export(dynamo=True)``) and run in ONNX
Runtime with the state fed back, against the same step in eager torch.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time

import numpy as np
import scipy.signal
import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import median_ms, table  # noqa: E402

from relightnet.light import preset_light, preset_names
from relightnet.sh import rotate_sh_up  # noqa: E402
from relightnet.temporal import (
    EMAFilter,
    FIRFilter,
    OneEuroFilter,
    OutlierGate,
    jitter,
    light_error,
    run_causal,
    smooth_lights,
    step_lag,
)
from relightnet.temporal.causal import ema_matrix, ema_sequence
from relightnet.temporal.distance import light_norm
from relightnet.temporal.metrics import outlier_scores
from relightnet.temporal.smoothers import savgol_matrix

T = 300


def make_sequence(seed: int):
    """(truth (T, 9, 3), noisy (T, 9, 3), spike flags (T,), switch frame)."""
    g = torch.Generator().manual_seed(seed)
    names = preset_names()
    i, j = torch.randperm(len(names), generator=g)[:2].tolist()
    a, b = preset_light(names[i]), preset_light(names[j])
    step = int(torch.randint(120, 181, (1,), generator=g))
    amp, freq, phase = (0.4 + 0.6 * torch.rand(3, generator=g)).tolist()
    t = torch.arange(T, dtype=torch.float64) / 30.0
    ang = amp * torch.sin(2 * math.pi * 0.25 * freq * t + 6 * phase)  # peak ≈ amp·π/2·freq rad/s
    truth = torch.stack([rotate_sh_up(a if k < step else b, float(ang[k])) for k in range(T)])
    rms = truth.square().mean((1, 2), keepdim=True).sqrt()  # per frame: noise relative to the light
    noisy = truth + 0.1 * rms * torch.randn(truth.shape, generator=g)
    allowed = torch.tensor([abs(k - step) > 3 for k in range(T)])
    cand = allowed.nonzero().flatten()
    idx = cand[torch.randperm(len(cand), generator=g)[: int(0.04 * T)]]
    spikes = torch.randn(len(idx), 9, 3, generator=g)
    spikes *= (0.5 * light_norm(truth[idx]) / light_norm(spikes))[:, None, None]
    noisy[idx] += spikes
    flags = torch.zeros(T, dtype=torch.bool)
    flags[idx] = True
    return truth, noisy, flags, step


def offline(method, eps="3mad", switches="auto", **opts):
    def run(x):
        r = smooth_lights(x, method, outlier_eps=eps, switches=switches, **opts)
        return r.smoothed, r.outliers

    return run


def causal(make, gated=False):
    def run(x):
        if not gated:
            return run_causal(make(), x), None
        y, states = run_causal(make(), x, return_states=True)
        return y, states[:, -1, 0, 0].round() == 1

    return run


METHODS = [
    ("hermite k=8, 3mad, switch split", "offline", offline("hermite", knot_spacing=8)),
    ("hermite k=8, 4mad, switch split", "offline", offline("hermite", "4mad", knot_spacing=8)),
    ("hermite k=8, 3mad, no split", "offline", offline("hermite", switches=None, knot_spacing=8)),
    ("hermite k=8, no outliers, no split", "offline", offline("hermite", None, None, knot_spacing=8)),
    ("poly local w=15 d=2, 3mad, split", "offline", offline("poly", degree=2, window=15)),
    ("savgol w=15 d=2, 3mad, split", "offline", offline("savgol", window=15, degree=2)),
    ("EMA α=0.3", "causal", causal(lambda: EMAFilter(0.3))),
    ("one-euro (0.5 Hz, β=1)", "causal", causal(lambda: OneEuroFilter(0.5, 1.0))),
    ("FIR box 5", "causal", causal(lambda: FIRFilter(5))),
    ("gate(3) + EMA α=0.3", "causal", causal(lambda: OutlierGate(EMAFilter(0.3)), True)),
    ("gate(3) + one-euro (0.5 Hz, β=1)", "causal", causal(lambda: OutlierGate(OneEuroFilter(0.5, 1.0)), True)),
    ("gate(3) + FIR box 5", "causal", causal(lambda: OutlierGate(FIRFilter(5)), True)),
    ("gate(3) + FIR linear 7", "causal", causal(lambda: OutlierGate(FIRFilter(7, 1)), True)),
    ("gate(3, persist 3) + one-euro", "causal", causal(lambda: OutlierGate(OneEuroFilter(0.5, 1.0), persist=3), True)),
]

ONNX_FILTERS = [
    ("EMA α=0.3", lambda: EMAFilter(0.3)),
    ("one-euro", lambda: OneEuroFilter(0.5, 1.0)),
    ("FIR box 5", lambda: FIRFilter(5)),
    ("gate(3) + one-euro", lambda: OutlierGate(OneEuroFilter(0.5, 1.0))),
]


def quality_table(seqs) -> str:
    raw_j, raw_e = [], []
    masks = []
    for truth, noisy, _, step in seqs:
        m = torch.ones(T, dtype=torch.bool)
        m[step - 10 : step + 10] = False
        masks.append(m)
        raw_j.append(jitter(noisy, mask=m).item())
        raw_e.append(light_error(noisy, truth).item())
    rows = [["raw input", "—", "0 %", "1", statistics.median(
        step_lag(n, t, s).item() for t, n, _, s in seqs), "—", "—", "—"]]
    for name, kind, fn in METHODS:
        jr, er, lags, rec, prec, us = [], [], [], [], [], []
        for (truth, noisy, flags, step), m, j0, e0 in zip(seqs, masks, raw_j, raw_e, strict=True):
            y, out = fn(noisy)
            jr.append(jitter(y, mask=m).item() / j0 - 1)
            er.append(light_error(y, truth).item() / e0)
            lags.append(step_lag(y, truth, step).item())
            if out is not None:
                r, p = outlier_scores(out, flags)
                rec.append(r)
                prec.append(p)
        truth, noisy, _, _ = seqs[0]
        us.append(median_ms(lambda fn=fn, x=noisy: fn(x), repeat=5) * 1e3 / T)
        med = statistics.median
        rows.append([
            name, kind, f"{100 * med(jr):+.1f} %", f"{med(er):.3f}", f"{med(lags):g}",
            f"{100 * med(rec):.0f} %" if rec else "—", f"{100 * med(prec):.0f} %" if prec else "—", f"{us[0]:.1f}",
        ])
    head = ["method", "kind", "jitter vs raw", "error / raw error", "lag to step (frames)", "outlier recall",
            "outlier precision", "µs/frame"]
    return table(head, rows)


def peer_table(seqs) -> str:
    rows = []
    _, noisy, _, _ = seqs[0]
    x = noisy.reshape(T, 27).double()
    xn = x.numpy()
    S = savgol_matrix(T, 15, 2)
    ours = median_ms(lambda: S @ x, repeat=21)
    build = median_ms(lambda: savgol_matrix(T, 15, 2), repeat=5)
    peer = median_ms(lambda: scipy.signal.savgol_filter(xn, 15, 2, axis=0, mode="interp"), repeat=21)
    diff = np.abs((S @ x).numpy() - scipy.signal.savgol_filter(xn, 15, 2, axis=0, mode="interp")).max()
    rows.append(["Savitzky–Golay w=15 d=2 (T×27)", f"S @ x (S prebuilt; build {build:.2f} ms)", ours, peer,
                 ours / peer, f"{diff:.1e}"])
    seq = noisy.double()
    alpha = 0.3
    ours_e = median_ms(lambda: ema_sequence(seq, alpha), repeat=21)

    def lfilter():
        zi = (1 - alpha) * xn[:1]
        return scipy.signal.lfilter([alpha], [1, -(1 - alpha)], xn, axis=0, zi=zi)[0]

    peer_e = median_ms(lfilter, repeat=21)
    diff_e = np.abs(ema_sequence(seq, alpha).reshape(T, 27).numpy() - lfilter()).max()
    rows.append(["EMA α=0.3 (T×27)", "ema_sequence (matrix built per call)", ours_e, peer_e, ours_e / peer_e,
                 f"{diff_e:.1e}"])
    M = ema_matrix(T, alpha, torch.float64)
    ours_m = median_ms(lambda: M @ x, repeat=21)
    rows.append(["EMA α=0.3 (T×27)", "M @ x (M prebuilt)", ours_m, peer_e, ours_m / peer_e, f"{diff_e:.1e}"])
    return table(["task", "ours", "ours (ms)", "SciPy (ms)", "ratio ours/SciPy", "max |diff|"], rows)


def onnx_table(seqs) -> str:
    """Per-frame cost of one causal step: eager torch vs the exported graph in ONNX Runtime (B = 1)."""
    import io
    import warnings

    import onnxruntime as ort

    _, noisy, _, _ = seqs[0]
    frames = noisy[:, None]  # (T, 1, 9, 3)
    rows = []
    for name, make in ONNX_FILTERS:
        filt = make()
        x0 = frames[0]
        state0 = filt.init_state(x0)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            prog = torch.onnx.export(filt, (x0, state0, torch.tensor([True])), dynamo=True, verbose=False,
                                     input_names=["x", "state", "is_first"], output_names=["y", "new_state"])
        buf = io.BytesIO(prog.model_proto.SerializeToString()).getvalue()
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = 1
        sess = ort.InferenceSession(buf, opts, providers=["CPUExecutionProvider"])
        xs = frames.numpy()

        def run_ort(sess=sess, xs=xs, state0=state0):
            st = state0.numpy()
            for t in range(T):
                y, st = sess.run(None, {"x": xs[t], "state": st, "is_first": np.array([t == 0])})
            return y

        def run_eager(filt=filt):
            with torch.no_grad():
                return run_causal(filt, noisy)

        eager = median_ms(run_eager, repeat=5) * 1e3 / T
        onnx = median_ms(run_ort, repeat=5) * 1e3 / T
        ref = run_causal(filt, noisy)[-1].numpy()
        rows.append([name, filt.state_size, f"{eager:.1f}", f"{onnx:.1f}", f"{np.abs(run_ort()[0] - ref).max():.1e}"])
    return table(["causal filter", "state slots S", "eager torch µs/frame", "ONNX Runtime µs/frame",
                  "max |ORT − torch| (last frame)"], rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seqs", type=int, default=8, help="number of synthetic sequences (default 8)")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    t0 = time.perf_counter()
    seqs = [make_sequence(s) for s in range(args.seqs)]
    print(f"## Temporal light smoothing: {args.seqs} sequences × {T} frames (medians)\n")
    print(quality_table(seqs))
    print("\n## Loop-free forms vs SciPy\n")
    print(peer_table(seqs))
    print("\n## One causal step: eager torch vs ONNX Runtime (B = 1, 1 ORT thread)\n")
    print(onnx_table(seqs))
    print(f"\n({time.perf_counter() - t0:.0f} s, {args.threads} threads, torch {torch.__version__})")


if __name__ == "__main__":
    main()
