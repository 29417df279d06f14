"""The records that travel between a driver and its workers: shard tasks and their failures,
batch-job results (frozen dataclasses, picklable, read by name rather than by position).

``relightnet synth`` hands :class:`ShardTask` records to its executors (the process itself, the
local pool, Ray) and gets back each shard's manifest entry, or a :class:`ShardFailure` once its
retries are spent; ``relightnet batch`` gets a :class:`JobResult` for every job, whichever runner
ran it, and :func:`relightnet.distributed.batch.summary_entry` turns it into the summary's format.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["ShardTask", "ShardFailure", "JobResult", "JOB_STATUSES"]

#: What a batch job's status can be (the summary's ``counts`` keys, in this order).
JOB_STATUSES = ("done", "skipped", "failed", "pending")


@dataclass(frozen=True)
class ShardTask:
    """Make shard ``index`` of ``split`` and write it (atomically) into ``out_dir``.

    ``config`` is the generator configuration as a plain dict (``SynthConfig.to_dict()``, so the
    record pickles without the data package), ``compression`` the shard's ``.npz`` compression.
    """

    config: dict
    split: str
    index: int
    out_dir: str
    compression: str

    @property
    def key(self) -> tuple[str, int]:
        """``(split, index)``: which shard, whatever its configuration."""
        return self.split, self.index


@dataclass(frozen=True)
class ShardFailure:
    """A shard that could not be made once its retries were spent: its one-line ``error`` and the
    ``attempts`` made (0 when the executor does not count them)."""

    split: str
    index: int
    error: str
    attempts: int = 0


@dataclass(frozen=True)
class JobResult:
    """How one batch job went: ``status`` (one of :data:`JOB_STATUSES`), the one-line ``error`` of a
    failure, the wall-clock ``seconds``, the ``attempts`` run, and the tail of its ``output`` (for its log)."""

    status: str
    error: str | None = None
    seconds: float = 0.0
    attempts: int = 0
    output: str = ""

    def __post_init__(self) -> None:
        if self.status not in JOB_STATUSES:
            raise ValueError(f"status: expected one of {', '.join(JOB_STATUSES)}, got {self.status!r}")

    @classmethod
    def failed(cls, error: str, seconds: float = 0.0, attempts: int = 0, output: str = "") -> JobResult:
        """A failure that says why in one line."""
        return cls("failed", error, seconds, attempts, output)
