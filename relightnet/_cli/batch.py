"""``relightnet batch``: many CLI jobs from one file, locally or on a Ray cluster."""

from __future__ import annotations

import argparse

from .argtypes import nonneg_int
from .options import add_command

_DESCRIPTION = """\
Run the jobs of a YAML (or JSON) file, each an existing relightnet command with its
arguments exactly as on the command line and its output at --out:

  jobs:
    - {command: relight-video, args: [in.mp4, --light, sunset, --out, out/a.mp4], resources: {cpus: 2}}
    - {command: relight-image, args: [person.png, --light, studio, --out, out/b.png]}
    - {command: render-body, args: [--motion, walk, --light, city, --out, out/walk.mp4], resources: {gpus: 1}}

Each job runs as its own process with its resources (cpus, default 1; gpus, default 0),
locally as many at once as they fit, or one Ray task per job with --ray. A bad entry
(unknown command, refused arguments, unreadable input) fails that job with its one-line
reason and the others go on; a crashed job is retried (--max-retries); a job whose --out
already exists complete is skipped, so running the same command again resumes. The
summary JOBS.summary.json (beside JOBS.yaml; per job: status done/skipped/failed, its
error, seconds) is rewritten after every job, each job's output goes to JOBS.logs/NNN.log,
and a table is printed at the end. Exit status 1 when a job failed. Relative paths are
relative to the folder batch runs in; on a cluster it must be one every node sees."""


def _table(summary: dict) -> str:
    rows = [("job", "command", "status", "seconds", "output or error")]
    for r in summary["jobs"]:
        rows.append((str(r["index"]), r["command"], r["status"], f"{r['seconds']:.1f}",
                     r["error"] if r["error"] else (r["out"] or "")))
    widths = [max(len(row[i]) for row in rows) for i in range(4)]
    lines = ["  ".join(c.ljust(w) for c, w in zip(row[:4], widths, strict=True)) + "  " + row[4] for row in rows]
    c = summary["counts"]
    lines.append(f"{c['done']} done, {c['skipped']} skipped, {c['failed']} failed"
                 + (f", {c['pending']} not run" if c["pending"] else ""))
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from ..distributed import RayOptions
    from ..distributed.batch import run_batch, summary_path

    ray = RayOptions(address=args.ray or None) if args.ray is not None else None
    summary = run_batch(args.jobs, args.commands, ray=ray, max_retries=args.max_retries, progress=not args.quiet)
    print(_table(summary))
    print(f"summary: {summary_path(args.jobs)}")
    return 1 if summary["counts"]["failed"] else 0


def register(sub) -> None:
    p = add_command(
        sub, "batch", "Run many relightnet jobs from a YAML file, locally or on a Ray cluster (resumable).",
        "  relightnet batch jobs.yaml                        # on this machine\n"
        "  relightnet batch jobs.yaml --ray                  # on the running Ray cluster, else a local one\n"
        "  relightnet batch jobs.yaml --ray head-node:6379   # on that cluster\n",
    )
    p.description = _DESCRIPTION
    p.add_argument("jobs", metavar="JOBS.yaml", help="the jobs file")
    p.add_argument("--ray", nargs="?", const="", metavar="ADDRESS",
                   help="one Ray task per job: on the running cluster (RAY_ADDRESS or 'ray start' here), else a "
                   "new local instance; ADDRESS: HOST:PORT of a head node, or 'local' (needs relightnet[ray])")
    p.add_argument("--max-retries", type=nonneg_int, default=1,
                   help="times a crashed job is run again; bad input is not retried (default: %(default)s)")
    # sub.choices: the command table (filled as the commands register), which the jobs are checked against
    p.set_defaults(func=run, commands=sub.choices,
                   interrupt_hint=lambda a: f"run the same command again to resume {a.jobs}")
