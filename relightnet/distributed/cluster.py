"""Connecting to a Ray cluster (the only place, with its siblings, that imports ``ray``).

``ray`` is an optional dependency (``pip install 'relightnet[ray]'``): everything outside
``relightnet.distributed`` works without it, and asking for ``--ray`` without it is a
one-line error.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Iterator
from dataclasses import dataclass

from ..checks import InputError

__all__ = ["RayOptions", "import_ray", "connect", "one_line", "default_workers"]

logger = logging.getLogger("relightnet.distributed")


@dataclass(frozen=True)
class RayOptions:
    """Where and how to run on Ray: ``address`` as :func:`connect` takes it, CPUs per task."""

    address: str | None = None
    cpus_per_task: float = 1.0


def import_ray():
    """The ``ray`` module, or a one-line :class:`InputError` saying how to install it."""
    try:
        import ray
    except ImportError as e:
        raise InputError(f"--ray: the 'ray' package is not importable ({e}); "
                         "install it with: pip install 'relightnet[ray]'") from None
    return ray


def _start_local(ray, num_cpus: int | None) -> None:
    ray.init(num_cpus=num_cpus, include_dashboard=False)
    logger.info("started a local Ray instance (%s CPUs)", int(ray.cluster_resources().get("CPU", 0)))


@contextlib.contextmanager
def connect(address: str | None = None, num_cpus: int | None = None) -> Iterator[object]:
    """Use a Ray cluster for the block; yields the ``ray`` module.

    Args:
        address: ``None``: a running cluster (``RAY_ADDRESS`` or one started on this machine by
            ``ray start``), else a new local instance; ``"local"``: always a new local instance;
            anything else (``HOST:PORT``, ``ray://HOST:PORT``, ``"auto"``) is passed to ``ray.init``.
            Ignored when this process is already connected (the caller's connection is used).
        num_cpus: CPUs of a new local instance (default: all).

    The connection made here is closed at the end of the block (a local instance stops).

    Raises:
        InputError: ray is not installed, or no cluster answers at ``address``.
    """
    ray = import_ray()
    if ray.is_initialized():
        yield ray
        return
    try:
        if address == "local":
            _start_local(ray, num_cpus)
        elif address is None:
            try:
                ray.init(address="auto")
            except ConnectionError:
                _start_local(ray, num_cpus)
        else:
            ray.init(address=address)
    except (ConnectionError, ValueError, RuntimeError) as e:
        with contextlib.suppress(Exception):
            ray.shutdown()
        raise InputError(f"--ray {address or ''}: cannot connect to a Ray cluster ({one_line(e)})") from None
    try:
        yield ray
    finally:
        ray.shutdown()


def one_line(e: BaseException) -> str:
    """``Type: message`` on one line; for a Ray task error, the task's own exception."""
    cause = getattr(e, "cause", None)
    if isinstance(cause, BaseException) and cause is not e:
        e = cause
    text = next((ln.strip() for ln in str(e).splitlines() if ln.strip()), "")
    return f"{type(e).__name__}: {text}" if text else type(e).__name__


def default_workers() -> int:
    """The CPUs this process may use (its affinity mask): the local pool's and batch's default."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)
