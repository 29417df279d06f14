"""Torch's intra-op thread count for a block of code, given back afterwards.

A library function that wants its own thread count (one thread for small tensors, where a second
thread only waits; one thread for reductions that must not depend on the machine's core count)
sets it with :func:`torch_threads`, so the caller's setting is the same after the call as before,
also when the block raises. Only code that owns its process (a command's ``--threads``, a worker
process's initialiser) sets the count for good.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import torch

from .errors import InputError

__all__ = ["torch_threads"]


@contextlib.contextmanager
def torch_threads(n: int) -> Iterator[None]:
    """Run the block with ``n`` intra-op threads (``torch.set_num_threads``), restoring the count on exit.

    Args:
        n: threads, at least 1.

    Raises:
        InputError: ``n`` below 1.

    Example:
        >>> import torch
        >>> before = torch.get_num_threads()
        >>> with torch_threads(1):
        ...     torch.get_num_threads()
        1
        >>> torch.get_num_threads() == before
        True
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise InputError(f"threads: expected an integer >= 1, got {n!r}")
    before = torch.get_num_threads()
    torch.set_num_threads(n)
    try:
        yield
    finally:
        torch.set_num_threads(before)
