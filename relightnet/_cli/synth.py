"""``relightnet synth``: make, verify or preview a synthetic dataset folder."""

from __future__ import annotations

import argparse
import logging
import math
import sys

from .argtypes import key_value_arg, nonneg_int, pos_float
from .options import add_command
from .paths import out_dir, out_file

logger = logging.getLogger("relightnet.synth")

#: --ray: CPUs reserved per shard task; --preview: rows of the sheet (when not given).
CPUS_PER_TASK, PREVIEW_ROWS = 1.0, 8

_DESCRIPTION = """\
Make a synthetic training set of people (Anny bodies, clothes, env-map and procedural lights)
with ground truth albedo, SH transport and light, as shards + manifest.json in --out.

Settings: SynthConfig defaults, then --config FILE, then the flags given. --count N sets the
train count; val and test keep the config's proportions to train (defaults 64:8:16, so
N/8 and N/4, rounded up) unless --split-count sets them. Running the same command again
resumes: finished shards are checked (sha256) and kept; other settings are an error.
--sequence T makes clips of T frames instead (shard_size clips per shard, a frame axis
after the sample axis).

--ray [ADDRESS] runs one Ray task per shard on a cluster (a running one, else a local
instance; ADDRESS: HOST:PORT of a head node, or 'local'); --out must then be a folder every
node sees. The shards are byte-identical to a local run. A shard that fails is retried
(--max-retries); one that keeps failing is named with its error and the exit status is 1."""


def _splits():
    from ..data.config import SPLITS

    return SPLITS


_split_count = key_value_arg(_splits, int, "SPLIT", "an integer")


def build_config(args: argparse.Namespace):
    """The SynthConfig the arguments ask for (config file, then flags)."""
    from ..checks import InputError
    from ..data import SynthConfig, load_config

    cfg = load_config(args.config) if args.config else SynthConfig()
    changes = {k: v for k, v in (("res", args.res), ("seed", args.seed), ("n_dirs", args.n_dirs),
                                 ("shard_size", args.shard_size), ("lmax", args.lmax),
                                 ("sequence_frames", args.sequence)) if v is not None}
    counts = dict(cfg.counts)
    if args.count is not None:
        if args.count < 0:
            raise InputError(f"--count: expected an integer >= 0, got {args.count}")
        base = max(1, counts.get("train", 0))
        for s in ("val", "test"):
            counts[s] = math.ceil(args.count * counts.get(s, 0) / base) if counts.get("train", 0) else counts.get(s, 0)
        counts["train"] = args.count
    for s, n in args.split_count or []:
        if n < 0:
            raise InputError(f"--split-count {s}: expected an integer >= 0, got {n}")
        counts[s] = n
    return cfg.replace(counts=counts, **changes)


def _verify(root: str) -> int:
    from ..data.shards import verify_dataset

    report = verify_dataset(root)
    if report.problems:
        for p in report.problems:
            sys.stderr.write(f"{p}\n")
        return 1
    counts = ", ".join(f"{s} {n}" for s, n in report.counts.items() if n)
    print(f"{root}: ok ({report.n_shards} shards; {counts or 'no'} samples)")
    return 0


def _refuse_unused(args: argparse.Namespace) -> None:
    """Options of one mode given in another are an error, not silently ignored."""
    from ..checks import InputError

    unused = {"--n": args.n is not None and not args.preview, "--split": args.split is not None and not args.preview,
              "--cpus-per-task": args.cpus_per_task is not None and args.ray is None,
              "--workers": args.workers is not None and args.ray is not None}
    making = ("--count", "--split-count", "--splits", "--res", "--seed", "--n-dirs", "--shard-size", "--lmax",
              "--sequence", "--config", "--workers", "--ray")
    if args.verify or args.preview:
        given = [o for o in making if getattr(args, o[2:].replace("-", "_")) is not None]
        unused.update(dict.fromkeys(given, True))
    bad = [o for o, u in unused.items() if u]
    if bad:
        mode = "--verify" if args.verify else "--preview" if args.preview else "--ray" if args.ray is not None \
            else "making a dataset"
        raise InputError(f"{', '.join(bad)}: not used with {mode}")


def run(args: argparse.Namespace) -> int:
    from ..checks import InputError

    _refuse_unused(args)
    if args.verify:
        return _verify(args.verify)
    if args.preview:
        from ..data.preview import preview

        out = out_file(args.out, suffixes=(".png",)) if args.out else None
        path = preview(args.preview, out, n=PREVIEW_ROWS if args.n is None else args.n, split=args.split)
        logger.info("wrote %s", path)
        return 0
    if not args.out:
        raise InputError("--out: a dataset folder is required (or use --verify DIR / --preview DIR)")
    from ..data.config import SPLITS
    from ..data.synth import run_synth
    from ..distributed.cluster import default_workers

    cfg = build_config(args)
    out = out_dir(args.out)
    workers = default_workers() if args.workers is None else args.workers
    if workers < 0:
        raise InputError(f"--workers: expected an integer >= 0, got {workers}")
    ray = None
    if args.ray is not None:
        from ..distributed import RayOptions

        ray = RayOptions(address=args.ray or None,
                         cpus_per_task=CPUS_PER_TASK if args.cpus_per_task is None else args.cpus_per_task)
    splits = None if not args.splits else [s.strip() for s in args.splits.split(",") if s.strip()]
    m = run_synth(out, cfg, workers=workers, splits=splits, progress=not args.quiet,
                  compression=args.compression, ray=ray, max_retries=args.max_retries)
    made = ", ".join(f"{s} {sum(e['count'] for e in v['shards'])}/{v['count']}"
                     for s, v in sorted(m["splits"].items(), key=lambda kv: SPLITS.index(kv[0])) if v["count"])
    logger.info("%s: %s (%s)", args.out, "complete" if m["complete"] else "partial", made)
    return 0


def register(sub) -> None:
    p = add_command(
        sub, "synth", "Make, verify or preview a synthetic dataset (shards + manifest.json).",
        "  relightnet synth --out data/synth --count 1000 --res 256 --seed 0 --workers 2\n"
        "  relightnet synth --out data/tiny --count 8 --res 64 --n-dirs 32 --split-count test=0\n"
        "  relightnet synth --out data/big --config synth.yaml --splits train\n"
        "  relightnet synth --out data/clips --sequence 16 --count 32 --res 128\n"
        "  relightnet synth --out /shared/data/big --count 100000 --ray            # running cluster, else local\n"
        "  relightnet synth --out /shared/data/big --count 100000 --ray head:6379 --cpus-per-task 1\n"
        "  relightnet synth --verify data/synth\n"
        "  relightnet synth --preview data/synth --out sheet.png --n 8\n",
    )
    p.description = _DESCRIPTION
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--verify", metavar="DIR", help="check a dataset folder (checksums, shapes, counts); "
                      "prints one line per problem and exits 1 if any")
    mode.add_argument("--preview", metavar="DIR", help="write a contact sheet PNG of a dataset folder (rows: samples; "
                      "columns: image, composite, albedo, shading, mask, normals, transport bands, occlusion)")
    p.add_argument("--out", help="dataset folder to make or resume; with --preview the PNG (default DIR/preview.png)")
    p.add_argument("--count", type=int, help="train samples (or clips); val/test follow the config's proportions")
    p.add_argument("--split-count", type=_split_count, action="append", metavar="SPLIT=N",
                   help="exact count of one split, e.g. val=50 or test=0; repeatable")
    p.add_argument("--splits", help="comma-separated splits to make now (default: all with a count)")
    p.add_argument("--res", type=int, help="image side in pixels, a multiple of 16 (default: 256)")
    p.add_argument("--seed", type=int, help="master seed (default: 0)")
    p.add_argument("--n-dirs", type=int, help="PRT directions of the ground-truth transport (default: 128)")
    p.add_argument("--shard-size", type=int, help="samples per shard file (default: 16)")
    p.add_argument("--lmax", type=int, help="SH order of lights and transports (default: 2, K = 9)")
    p.add_argument("--sequence", type=int, metavar="T", help="make clips of T frames instead of still samples")
    p.add_argument("--config", help="a .yaml/.json SynthConfig file (flags override its values)")
    p.add_argument("--workers", type=int, help="generator processes (default: the CPUs available; 0: in-process; "
                   "not used with --ray)")
    p.add_argument("--ray", nargs="?", const="", metavar="ADDRESS",
                   help="run one Ray task per shard: on the running cluster (RAY_ADDRESS or 'ray start' here), "
                   "else a new local instance; ADDRESS: HOST:PORT of a head node, or 'local' (needs relightnet[ray])")
    p.add_argument("--cpus-per-task", type=pos_float, default=None,
                   help=f"--ray: CPUs reserved per shard task (default: {CPUS_PER_TASK:g})")
    p.add_argument("--max-retries", type=nonneg_int, default=2,
                   help="times a shard that raised or whose worker process (or Ray node) died is tried again "
                   "(default: %(default)s)")
    p.add_argument("--compression", choices=("deflate", "store"), default="deflate",
                   help="shard compression (default: %(default)s)")
    p.add_argument("--n", type=int, default=None,
                   help=f"--preview: samples (rows) in the sheet (default: {PREVIEW_ROWS})")
    p.add_argument("--split", help="--preview: split to show (default: the first with shards)")
    p.set_defaults(func=run, interrupt_hint=lambda a: f"run the same command again to resume {a.out}")
