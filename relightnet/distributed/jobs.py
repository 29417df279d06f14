"""Batch job files: their form, checking each entry against the CLI, and running one job.

A jobs file (YAML or JSON) holds ``jobs``, a list of entries::

    jobs:
      - command: relight-video
        args: [in.mp4, --light, sunset, --out, out/a.mp4]   # exactly as on the command line
        resources: {cpus: 2}                                 # optional: cpus (default 1), gpus (default 0)
      - command: relight-image
        args: [person.png, --light, studio, --out, out/b.png]

Other keys are ignored (tools may add their own). A job's output is its ``--out``. The
commands a job may run are those of the ``relightnet`` CLI itself (its command table, handed
in by the caller, so new commands join by themselves), except ``batch``. An entry that is not a job — an
unknown command, arguments the command's parser refuses, no ``--out`` — becomes a failed
job with its one-line reason; the other jobs still run. Relative paths in ``args`` are
relative to the folder ``relightnet batch`` runs in (as they would be on the command line).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from ..checks import InputError
from ..io.documents import short
from .records import JobResult

__all__ = ["Job", "load_jobs", "batchable_commands", "execute_job", "NOT_BATCHABLE"]

#: CLI commands a job may not run (a batch inside a batch).
NOT_BATCHABLE = ("batch",)

_LOG_TAIL = 20_000  # characters of a job's output kept for its log


@dataclass(frozen=True)
class Job:
    """One entry of a jobs file: ``error`` is set (and the job is not run) when the entry is bad."""

    index: int
    command: str
    args: tuple[str, ...]
    out: str | None = None
    cpus: float = 1.0
    gpus: float = 0.0
    error: str | None = None
    extra: dict = field(default_factory=dict, compare=False)

    def record(self) -> dict:
        """The entry as the summary shows it."""
        return {"index": self.index, "command": self.command, "args": list(self.args), "out": self.out,
                "resources": {"cpus": self.cpus, "gpus": self.gpus}}


def batchable_commands(commands: Mapping[str, argparse.ArgumentParser]) -> list[str]:
    """The commands a job may run: every command of the table but :data:`NOT_BATCHABLE`.

    Args:
        commands: the CLI's command table, {name: the command's parser} (``relightnet batch`` passes
            its own; :func:`relightnet.cli.command_table` builds it). This package sits below the
            CLI and never imports it.
    """
    return [name for name in commands if name not in NOT_BATCHABLE]


def _parse(parser: argparse.ArgumentParser, argv: list[str]) -> tuple[argparse.Namespace | None, str]:
    """Parse ``argv`` as the CLI would; (namespace, "") or (None, argparse's one-line complaint)."""
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            return parser.parse_args(argv), ""
    except SystemExit:
        lines = [ln for ln in err.getvalue().splitlines() if ln.strip()]
        return None, lines[-1].split(" error: ", 1)[-1] if lines else "arguments not accepted (e.g. --help)"


def _resources(entry: dict) -> tuple[float, float]:
    res = entry.get("resources") or {}
    if not isinstance(res, dict):
        raise ValueError(f"resources: expected a mapping such as {{cpus: 2, gpus: 1}}, got {short(res)}")
    cpus, gpus = res.get("cpus", 1), res.get("gpus", 0)
    for name, v, lo in (("cpus", cpus, "> 0"), ("gpus", gpus, ">= 0")):
        if isinstance(v, bool) or not isinstance(v, int | float) or not (v > 0 if name == "cpus" else v >= 0):
            raise ValueError(f"resources.{name}: expected a number {lo}, got {short(v)}")
    return float(cpus), float(gpus)


def _job(index: int, entry, table: Mapping[str, argparse.ArgumentParser], commands: list[str]) -> Job:
    """Check one entry; a bad one comes back as a Job with ``error`` set."""
    if not isinstance(entry, dict):
        return Job(index, "?", (), error=f"expected a mapping with command and args, got {type(entry).__name__}")
    command, args = entry.get("command"), entry.get("args", [])
    shown = command[:40] if isinstance(command, str) else "?" if command is None else short(command, 40)
    if not isinstance(args, list) or any(isinstance(a, dict | list | bool) or a is None for a in args):
        return Job(index, shown, (),
                   error=f"args: expected a list of strings as on the command line, got {short(args)}")
    args = tuple(str(a) for a in args)
    if command not in commands:
        return Job(index, shown, args,
                   error=f"unknown command {short(command, 40)}: expected one of {', '.join(commands)}")
    try:
        cpus, gpus = _resources(entry)
    except ValueError as e:
        return Job(index, command, args, error=str(e))
    ns, complaint = _parse(table[command], list(args))
    if ns is None:
        return Job(index, command, args, cpus=cpus, gpus=gpus, error=complaint)
    out = getattr(ns, "out", None)
    if not out:
        return Job(index, command, args, cpus=cpus, gpus=gpus,
                   error=f"{command} {' '.join(args)}: no --out (a batch job's output is its --out)")
    extra = {k: v for k, v in entry.items() if k not in ("command", "args", "resources")}
    return Job(index, command, args, str(out), cpus, gpus, extra=extra)


def load_jobs(path, commands: Mapping[str, argparse.ArgumentParser]) -> list[Job]:
    """Read and check a jobs file (module docstring); bad entries come back with ``error`` set.

    Args:
        path: the YAML/JSON jobs file.
        commands: the CLI's command table, {name: parser} (:func:`batchable_commands`).

    Raises:
        InputError: the file is missing, unreadable, not YAML/JSON, or has no ``jobs`` list.
    """
    from ..io.documents import read_document

    path = Path(path)
    data = read_document(path, "jobs file")
    if not isinstance(data, dict) or not isinstance(data.get("jobs"), list):
        raise InputError(f"{path}: expected a mapping with a 'jobs' list ({{jobs: [{{command: ..., args: [...]}}]}})")
    names = batchable_commands(commands)
    jobs, outputs = [], {}
    for i, entry in enumerate(data["jobs"]):
        job = _job(i, entry, commands, names)
        if job.error is None:
            key = os.path.normpath(job.out)
            if key in outputs:
                job = Job(i, job.command, job.args, job.out, job.cpus, job.gpus,
                          error=f"--out {job.out}: job {outputs[key]} writes it too")
            else:
                outputs[key] = i
        jobs.append(job)
    return jobs


def _why(output: str, returncode: int, command: str) -> tuple[str, bool]:
    """(the one line that says why a job failed, whether it is bad input that a retry would not fix).

    The line is the job's last line of output (the CLI's one-line error without its
    ``relightnet COMMAND:`` prefix, or a traceback's last line), or the signal that killed it.
    """
    if returncode < 0:
        with contextlib.suppress(ValueError):
            return f"killed by {signal.Signals(-returncode).name}", False
        return f"killed by signal {-returncode}", False
    lines = [ln.strip() for ln in output.replace("\r", "\n").splitlines() if ln.strip()]
    last = lines[-1] if lines else f"exit status {returncode}"
    prefix = f"relightnet {command}: "
    if last.startswith(prefix):
        return last[len(prefix):], returncode in (1, 2)
    return last, returncode == 2  # 2: argparse refused the arguments


def execute_job(job: Job, cwd: str, max_retries: int = 1, env: dict | None = None) -> JobResult:
    """Run one job as a ``relightnet`` subprocess in ``cwd`` (this machine, or a Ray worker's node).

    A failure the CLI reported as bad input (its one-line error, exit status 1, or a usage
    error, 2) is not retried; any other (a crash, a signal) is run again up to ``max_retries`` times.

    Args:
        env: variables added to this process's environment for the job (e.g. ``OMP_NUM_THREADS``).

    Returns:
        A :class:`~relightnet.distributed.records.JobResult`, done or failed (``output``: the tail of
        the job's stdout and stderr, for its log).
    """
    import socket

    t0 = time.monotonic()
    if not Path(cwd).is_dir():
        return JobResult.failed(f"{cwd}: not found on node {socket.gethostname()}; run batch from a folder every "
                                "node sees")
    cmd = [sys.executable, "-m", "relightnet.cli", job.command, *job.args]
    child_env = {**os.environ, **(env or {})}
    output, error, attempt = "", None, 0
    for attempt in range(1, int(max_retries) + 2):
        with tempfile.TemporaryFile() as log:
            rc = subprocess.run(cmd, cwd=cwd, env=child_env, stdin=subprocess.DEVNULL, stdout=log,
                                stderr=subprocess.STDOUT).returncode
            log.seek(max(0, log.seek(0, os.SEEK_END) - 4 * _LOG_TAIL))
            output = log.read().decode("utf-8", "replace")[-_LOG_TAIL:]
        if rc == 0:
            return JobResult("done", None, time.monotonic() - t0, attempt, output)
        error, bad_input = _why(output, rc, job.command)
        if bad_input:
            break  # the same again would fail the same way
    return JobResult.failed(error, time.monotonic() - t0, attempt, output)
