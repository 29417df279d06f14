"""synth on Ray vs the local process pool: samples/s on this machine, Ray's start-up apart.

Run: ``.venv/bin/python benchmarks/bench_ray.py [--n 16] [--res 256] [--repeat 2]`` (ANNY_CACHE_DIR set by make).

Both executors run the same shard tasks (``relightnet.data.pool.shard_task``: generate with
one torch thread, write the shard atomically): a :class:`LocalPool` of 2 processes and a
local 2-CPU Ray instance (loopback only). Measured side by side in one run:

1. Ray's start-up, apart: ``ray.init`` (a local 2-CPU instance); the pool's start-up
   (forkserver, worker processes) beside it.
2. One warm-up run on each, the same shards (workers import relightnet, build the body
   assets and fill their memos of env maps and clothing regions), timed apart.
3. Then, "once started": runs of the same n samples on each, interleaved, wall time from
   submitting the shards to the last one written; samples/s = n / wall (medians).
   Ray's overhead = 1 − Ray/pool (goal on 2 cores: ≤ 10%). Ray's workers run at this
   process's priority, as the pool's do (``RAY_worker_niceness=0``; Ray's default lowers them
   by 15, which matters only on a machine shared with other jobs).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time

os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")  # a local instance on 127.0.0.1 only
# Ray lowers its workers' priority by 15 by default; on a machine shared with other jobs that
# alone slows them against the pool's workers (which keep this process's priority).
os.environ.setdefault("RAY_worker_niceness", "0")

import torch  # noqa: E402

sys.path.insert(0, os.path.dirname(__file__))
from common import table  # noqa: E402

from relightnet.data import SynthConfig  # noqa: E402
from relightnet.data.pool import LocalPool, shard_task  # noqa: E402
from relightnet.distributed.ray_synth import run_ray_shards  # noqa: E402
from relightnet.distributed.records import ShardTask  # noqa: E402

WORKERS = 2


def _run(executor, cfg: SynthConfig, shards: range) -> float:
    """Wall seconds of one run of these shards on ``executor`` (a LocalPool, or None for Ray)."""
    with tempfile.TemporaryDirectory() as d:
        tasks = [ShardTask(cfg.to_dict(), "train", i, d, "deflate") for i in shards]
        t0 = time.perf_counter()
        if executor is not None:
            executor.run(tasks, on_result=lambda r: None, on_tick=lambda k: None)
        else:
            run_ray_shards(shard_task, tasks, on_result=lambda r: None, on_tick=lambda k: None)
        return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=16, help="samples per measured run (default: 16)")
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--shard-size", type=int, default=4)
    ap.add_argument("--repeat", type=int, default=3, help="runs per executor, interleaved (default: 3)")
    ap.add_argument("--warmup", type=int, default=16, help="samples of the warm-up run on each (default: 16)")
    args = ap.parse_args()
    import ray

    n_shards = args.n // args.shard_size
    cfg = SynthConfig(res=args.res, shard_size=args.shard_size, counts={"train": 10_000, "val": 0, "test": 0})
    cpu = next((ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo") if ln.startswith("model name")), "?")
    print(f"## synth: local pool vs Ray, {args.res}², {cfg.n_dirs} PRT directions, shards of {args.shard_size}, "
          f"{WORKERS} workers; {cpu}, {os.cpu_count()} CPUs, torch {torch.__version__}, ray {ray.__version__}\n")
    t0 = time.perf_counter()
    ray.init(num_cpus=WORKERS, include_dashboard=False)
    t_init = time.perf_counter() - t0
    t0 = time.perf_counter()
    pool = LocalPool(WORKERS)
    t_pool = time.perf_counter() - t0
    warm = range(100, 100 + args.warmup // args.shard_size)
    try:
        warm_s = {"pool": _run(pool, cfg, warm), "ray": _run(None, cfg, warm)}
        walls = {"pool": [], "ray": []}
        for r in range(args.repeat):  # interleaved, so both see the same machine noise
            shards = range(r * n_shards, (r + 1) * n_shards)
            walls["pool"].append(_run(pool, cfg, shards))
            walls["ray"].append(_run(None, cfg, shards))
    finally:
        pool.close()
        ray.shutdown()
    print(table(["start-up (apart)", "s"], [
        ["ray.init (a local 2-CPU instance)", t_init],
        ["LocalPool() (forkserver; its workers start in the warm-up run)", t_pool],
        [f"warm-up run on the pool ({args.warmup} samples; assets, memos)", warm_s["pool"]],
        [f"warm-up run on Ray ({args.warmup} samples; worker processes, assets, memos)", warm_s["ray"]]]))
    rate = {ex: args.n / statistics.median(v) for ex, v in walls.items()}
    print()
    print(table(["executor (once started)", "samples/s (median)", "wall s (median)", "runs (s)", "vs pool"],
                [[ex, rate[ex], statistics.median(v), " ".join(f"{w:.1f}" for w in v),
                  f"{rate[ex] / rate['pool']:.3f}x"] for ex, v in walls.items()]))
    print(f"\nRay's overhead once started: {100 * (1 - rate['ray'] / rate['pool']):.1f}% (goal ≤ 10%); "
          f"{args.repeat} interleaved runs of {args.n} samples each")


if __name__ == "__main__":
    main()
