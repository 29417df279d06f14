"""A test-only fault hook for ``relightnet synth``: make one shard's process die mid-shard.

The tests of retries (a worker that dies, a Ray task that fails, a shard that keeps killing
its worker) need a real process to exit at a chosen point. This module is the only place that
knows how; the library's normal path asks :func:`fault_spec` once per run and, when it is None
(the variable unset, always outside tests), never imports anything else from here.

With ``RELIGHTNET_SYNTH_FAULT=SHARD`` in the driver's environment (``SHARD`` a file name such as
``train-00001.npz``) the process making that shard exits (``os._exit(70)``) after its first
sample, i.e. mid-shard, every time; ``SHARD@MARKER`` does so only while the file ``MARKER`` does
not exist (it is created just before), i.e. on the first attempt only. The driver reads the
variable and hands the spec to the tasks, so it reaches workers on any executor.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

__all__ = ["FAULT_ENV", "fault_spec", "faulty_tick"]

logger = logging.getLogger("relightnet.data.synth")

#: The environment variable of the hook (read by the driver).
FAULT_ENV = "RELIGHTNET_SYNTH_FAULT"


def fault_spec() -> str | None:
    """The hook's spec from the driver's environment, or None (the normal case)."""
    return os.environ.get(FAULT_ENV) or None


def faulty_tick(fault: str, shard: str, tick):
    """``tick`` (called after every sample of ``shard``) replaced by one that exits the process,
    when ``fault`` names ``shard``; else ``tick`` unchanged."""
    name, _, marker = fault.partition("@")
    if name != shard:
        return tick

    def die() -> None:
        if marker:
            if Path(marker).exists():
                if tick is not None:
                    tick()
                return
            Path(marker).touch()
        logger.warning("%s: fault hook (%s): this process exits now", name, FAULT_ENV)
        os._exit(70)

    return die
