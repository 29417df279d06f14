"""Synthetic data generator throughput: samples/s at 256² with 1 and 2 worker processes.

Run: ``.venv/bin/python benchmarks/bench_synth.py [--n 16] [--res 256]`` (ANNY_CACHE_DIR set by make).

1. Where a sample's time goes (one process, one torch thread, as a worker runs): body
   model, PRT (``vertex_transport`` with and without occlusion), raster (``render_mesh``,
   ``interpolate``, ``antialias``), the rest of the generator (lights, textures,
   backgrounds, framing), and the shard write (stack + deflate + sha256). The phases are
   timed by wrapping those functions for this run only. Medians over samples.
2. Throughput of ``run_synth``'s pool (W workers, each generating and writing whole shards),
   steady state from the moment every worker has made its first sample to the last shard
   written, W = 1 and 2 side by side, and the ratio. Goal: ≥ 2 samples/s with 2 workers on 2 cores.
3. One whole ``run_synth`` call with 2 workers (pool start-up, manifest, checksums included).

``--clothes`` runs instead, side by side in one run (interleaved repeats, 128² and 256²): the
painted generator without PRT reuse (what version 1 made: every garment painted on the body,
one PRT per sample), clothed without reuse, and clothed with ``prt_reuse`` 4 and 8 (one posed,
clothed body's PRT turned into 4 or 8 cameras' light frames). It measures *CPU* seconds per
sample of one single-threaded process generating and writing a shard, as a pool worker does:
on a loaded machine wall-clock rates say more about the neighbours than about the generator,
while the workers share nothing, so 2 workers on 2 free cores make 2 / (CPU s per sample)
samples/s (pool start-up aside). Then, over ``--n`` stills at 64², the garment types worn
and, per type, the share of samples where body shows through cloth (``hidden_body_share`` >
1 % of the cloth's pixels) and its mean.

``--cpu-still START`` prints one line, ``CPU_MS_PER_STILL KB_PER_STILL``: this process, single-threaded,
generates 24 warm-up stills and then ``--n`` stills from START of ``--config`` (default
``train/configs/data_clothed.yaml``; ``--res`` overrides its size) group by group and writes them as
one shard, as a pool worker does (``_cpu_per_sample``). Run it alternately with ``PYTHONPATH`` at two
checkouts to compare code on a loaded machine (BENCHMARKS.md, "Casting only what the views show").
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import torch

sys.path.insert(0, os.path.dirname(__file__))
from common import table  # noqa: E402

from relightnet.body import AnnyBody  # noqa: E402
from relightnet.data import SynthConfig, pool, synth  # noqa: E402
from relightnet.data import render_sample as rs  # noqa: E402
from relightnet.data.generate import generate_sample, prepare_assets  # noqa: E402
from relightnet.data.shards import stack_samples, write_shard  # noqa: E402

_PHASES = {"PRT": ("person_transport",), "raster": ("rasterize", "render_mesh", "interpolate", "antialias")}


def _timed(fn, bucket: list):
    def wrapper(*a, **k):
        t0 = time.perf_counter()
        try:
            return fn(*a, **k)
        finally:
            bucket[0] += time.perf_counter() - t0
    return wrapper


def bench_phases(cfg: SynthConfig, n: int) -> list:
    """Per-phase medians (ms/sample) of n samples generated in this process, one thread."""
    torch.set_num_threads(1)
    assets = prepare_assets()
    buckets = {name: [0.0] for name in ("body", *_PHASES)}
    saved = {f: getattr(rs, f) for fs in _PHASES.values() for f in fs}
    forward = AnnyBody.forward
    for phase, fs in _PHASES.items():
        for f in fs:
            setattr(rs, f, _timed(saved[f], buckets[phase]))
    AnnyBody.forward = _timed(forward, buckets["body"])
    per = defaultdict(list)
    samples = []
    try:
        generate_sample(cfg, "train", 10_000, assets)  # warm-up: env maps, region labels
        for i in range(n):
            for b in buckets.values():
                b[0] = 0.0
            t0 = time.perf_counter()
            samples.append(generate_sample(cfg, "train", i, assets))
            total = time.perf_counter() - t0
            for k, b in buckets.items():
                per[k].append(b[0])
            per["other generator work"].append(total - sum(b[0] for b in buckets.values()))
            per["generate (total)"].append(total)
    finally:
        for f, fn in saved.items():
            setattr(rs, f, fn)
        AnnyBody.forward = forward
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        arrays = stack_samples(samples)
        info = write_shard(Path(d) / "train-00000.npz", arrays)
        per["write (stack + deflate + sha256)"] = [(time.perf_counter() - t0) / n]
    med = {k: statistics.median(v) * 1e3 for k, v in per.items()}
    total = med["generate (total)"] + med["write (stack + deflate + sha256)"]
    rows = [[k, med[k], f"{100 * med[k] / total:.0f}%"] for k in
            ("body", "PRT", "raster", "other generator work", "write (stack + deflate + sha256)")]
    rows.append(["total", total, "100%"])
    return rows, info["bytes"] / n / 1e6


def bench_pool(cfg: SynthConfig, workers: int, n: int) -> tuple[float, float]:
    """Steady-state samples/s of run_synth's pool (workers generate and write whole shards), and start-up s."""
    stamps = []
    with tempfile.TemporaryDirectory() as d:
        tasks = [(cfg.to_dict(), "train", i, d, "deflate") for i in range(n // cfg.shard_size)]
        t_start = time.perf_counter()
        pool.run_pool(tasks, workers, on_result=lambda r: None, on_tick=lambda n: stamps.append(time.perf_counter()))
        t_end = time.perf_counter()
    # Every worker has made its first sample (its first group of cfg.prt_reuse stills: a shard's
    # samples are reported group by group, so the steady state starts after those).
    skip = workers * min(cfg.prt_reuse, cfg.shard_size)
    first = sorted(stamps)[skip - 1]
    return (len(stamps) - skip) / (t_end - first), first - t_start


_PAINTED = {"upper": {"none": 1}, "lower": {"none": 1}, "head": {"none": 1}, "hair": {"painted": 1}}


def _cpu_per_sample(cfg: SynthConfig, start: int, n: int, assets) -> float:
    """CPU seconds per sample of this process generating stills start … start + n − 1 group by group (as a
    worker does) and writing them as one shard (stack + deflate + sha256)."""
    from relightnet.data.generate import generate_samples

    t0 = time.process_time()
    samples = generate_samples(cfg, "train", range(start, start + n), assets)
    with tempfile.TemporaryDirectory() as d:
        write_shard(Path(d) / "train-00000.npz", stack_samples(samples))
    return (time.process_time() - t0) / n


def cpu_still(args) -> None:
    """``--cpu-still``: one line, CPU ms and shard kB per still (module docstring)."""
    from relightnet.data.config import load_config
    from relightnet.data.generate import generate_samples

    torch.set_num_threads(1)
    cfg = load_config(args.config)
    cfg = cfg if args.res is None else cfg.replace(res=args.res)
    assets = prepare_assets()
    generate_samples(cfg, "train", range(10**6, 10**6 + 24), assets)  # env maps, clothing variants' regions
    t0 = time.process_time()
    samples = generate_samples(cfg, "train", range(args.cpu_still, args.cpu_still + args.n), assets)
    with tempfile.TemporaryDirectory() as d:
        info = write_shard(Path(d) / "train-00000.npz", stack_samples(samples))
    print(f"{1e3 * (time.process_time() - t0) / args.n:.1f} {info['bytes'] / args.n / 1e3:.1f}")


def bench_clothes(args) -> None:
    """Painted vs clothed, PRT reuse 1 / 4 / 8: CPU s per sample side by side, then body-through-cloth per type."""
    torch.set_num_threads(1)
    assets = prepare_assets()
    setups = [("painted, no reuse (v1)", dict(garment_probs=_PAINTED, prt_reuse=1)),
              ("clothed, no reuse", dict(prt_reuse=1)), ("clothed, reuse 4", dict(prt_reuse=4)),
              ("clothed, reuse 8", dict(prt_reuse=8))]
    for res in (128, 256):
        for _, kw in setups:  # warm-up: env maps, region labels of common variants
            _cpu_per_sample(SynthConfig(res=res, **kw), 10**6, 8, assets)
        runs = {name: [] for name, _ in setups}
        for rep in range(args.repeat):  # interleaved, so every setup sees the same machine noise
            for name, kw in setups:
                runs[name].append(_cpu_per_sample(SynthConfig(res=res, **kw), 1000 * (rep + 1), args.n, assets))
        med = {k: statistics.median(v) for k, v in runs.items()}
        base = med[setups[0][0]]
        print(f"\n### {res}², one process, one thread, {args.n} samples per run, median of {args.repeat}\n")
        print(table(["generator", "CPU ms / sample", "samples per CPU-s", "2 workers on 2 free cores, samples/s",
                     "vs painted v1", "vs goal 10/s"],
                    [[k, 1e3 * v, 1 / v, 2 / v, f"{base / v:.2f}x", f"{2 / v / 10:.2f}x"] for k, v in med.items()]))
    from relightnet.data.garments import GARMENT_TYPES
    from relightnet.data.generate import generate_samples

    metas = [s.meta for s in generate_samples(SynthConfig(res=64, prt_reuse=1), "train", range(args.n_quality),
                                              assets)]
    rows = []
    for t in GARMENT_TYPES:
        share = [m["garments"]["hidden_body_share"] for m in metas if t in m["garments"]["types"]]
        rows.append([t, len(share), f"{100 * len(share) / len(metas):.0f}%",
                     f"{100 * sum(x > 0.01 for x in share) / max(len(share), 1):.1f}%",
                     f"{100 * statistics.mean(share) if share else 0:.2f}%"])
    print(f"\n### Garments in {len(metas)} default stills (64², one person each)\n")
    print(table(["type", "samples", "share of samples", "body through cloth > 1 %", "mean through-share"], rows))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=16, help="samples per measurement (default: 16)")
    ap.add_argument("--res", type=int, default=None, help="image size (default: 256; --cpu-still: the config's)")
    ap.add_argument("--cpu-still", type=int, default=None, metavar="START",
                    help="print CPU ms and shard kB per still of --n stills from START (see above)")
    ap.add_argument("--config", default="train/configs/data_clothed.yaml", help="the config of --cpu-still")
    ap.add_argument("--repeat", type=int, default=3, help="pool runs per worker count (default: 3)")
    ap.add_argument("--clothes", action="store_true", help="painted vs clothed, PRT reuse 1/4/8 (see above)")
    ap.add_argument("--n-quality", type=int, default=96, help="stills for the garment table of --clothes")
    args = ap.parse_args()
    if args.cpu_still is not None:
        return cpu_still(args)
    args.res = args.res or 256
    if args.clothes:
        print(f"## Synthetic data with clothes: {os.cpu_count()} CPUs, torch {torch.__version__}")
        return bench_clothes(args)
    cfg = SynthConfig(res=args.res, shard_size=8)
    print(f"## Synthetic data: {args.res}², K = {cfg.n_coeffs}, {cfg.n_dirs} PRT directions, "
          f"{os.cpu_count()} CPUs, torch {torch.__version__}\n")
    rows, mb = bench_phases(cfg, max(4, args.n // 2))
    print(table(["phase (1 process, 1 thread)", "ms / sample (median)", "share"], rows))
    print(f"\nshard size: {mb:.2f} MB per sample (deflate)\n")
    runs = {1: [], 2: []}
    for _ in range(args.repeat):  # interleaved, so both see the same machine noise
        for w in runs:
            runs[w].append(bench_pool(cfg, w, args.n))
    res = {w: (statistics.median(r for r, _ in v), statistics.median(s for _, s in v)) for w, v in runs.items()}
    print(table(["workers", "samples/s (steady, median)", "pool start-up s", "vs 1 worker", "vs goal 2/s"],
                [[w, r, s, f"{r / res[1][0]:.2f}x", f"{r / 2.0:.2f}x"] for w, (r, s) in res.items()]))
    print(f"\n(medians of {args.repeat} runs of {args.n} samples in shards of {cfg.shard_size}; start-up = until "
          "every worker has made its first sample, with the forkserver already running)")
    with tempfile.TemporaryDirectory() as d:
        c = cfg.replace(counts={"train": args.n, "val": 0, "test": 0})
        t0 = time.perf_counter()
        synth.run_synth(Path(d) / "ds", c, workers=2, progress=False)
        wall = time.perf_counter() - t0
    print(f"\nrun_synth end to end, 2 workers, {args.n} samples: {wall:.1f} s = {args.n / wall:.2f} samples/s "
          "(pool start-up, manifest and checksums included)")


if __name__ == "__main__":
    main()
