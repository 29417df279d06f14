"""A streaming job's reading and writing in their own threads: frames read ahead, results written behind.

A video job reads a frame (decoding, and finding the person in it), relights it, and writes it
(encoding). Run in one thread, each stage waits for the others; PyAV's codecs, ONNX Runtime and
torch's kernels release the GIL, so :class:`ReadAhead` (an iterator filled by a thread) and
:class:`WriteBehind` (a writer fed through a queue) let the three overlap on the cores. Both keep
the order of the items, hold at most ``depth`` of them (memory stays bounded), and hand an
exception raised in their thread to the caller at its next call. Leaving either's ``with`` block
early (an error, a ``break``) stops its thread and drops what it holds.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable, Iterable

__all__ = ["ReadAhead", "WriteBehind"]

_END = object()
_POLL_S = 0.05


class ReadAhead:
    """Iterate ``items`` in a thread, ``depth`` items ahead of the caller.

    Use as ``with ReadAhead(frames) as ahead: for x in ahead: ...``. The source iterator is closed
    (its ``close()``, for a generator: its ``finally`` blocks) in the thread when it ends or when
    the block is left."""

    def __init__(self, items: Iterable, depth: int = 2, name: str = "read-ahead") -> None:
        if depth < 1:
            raise ValueError(f"depth: expected at least 1, got {depth}")
        self._items, self._q = items, queue.Queue(maxsize=depth)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def _put(self, x) -> bool:
        while not self._stop.is_set():
            try:
                self._q.put(x, timeout=_POLL_S)
                return True
            except queue.Full:
                continue
        return False

    def _run(self) -> None:
        it = iter(self._items)
        try:
            for x in it:
                if not self._put((x, None)):
                    return
            self._put((_END, None))
        except BaseException as e:  # handed to the caller, raised there
            self._put((_END, e))
        finally:
            close = getattr(it, "close", None)
            if close is not None:
                close()

    def __enter__(self) -> ReadAhead:
        self._thread.start()
        return self

    def __iter__(self) -> ReadAhead:
        return self

    def __next__(self):
        x, err = self._q.get()
        if x is _END:
            self._q.put((_END, None))  # a later next() ends too
            if err is not None:
                raise err
            raise StopIteration
        return x

    def __exit__(self, *exc) -> None:
        self._stop.set()
        while self._thread.is_alive():
            try:
                self._q.get(timeout=_POLL_S)  # unblock a put
            except queue.Empty:
                pass
        self._thread.join()


class WriteBehind:
    """Call ``write(*args, **kwargs)`` for each :meth:`put` in a thread, in order, ``depth`` calls behind.

    Use as ``with WriteBehind(writer.write) as behind: behind.put(frame, time=t)``. Leaving the
    block normally waits for every write and raises the first error a write raised; leaving it
    with an exception drops the writes not yet made."""

    def __init__(self, write: Callable, depth: int = 2, name: str = "write-behind") -> None:
        if depth < 1:
            raise ValueError(f"depth: expected at least 1, got {depth}")
        self._write, self._q = write, queue.Queue(maxsize=depth)
        self._error: BaseException | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def _run(self) -> None:
        while True:
            item = self._q.get()
            if item is _END or self._stop.is_set():
                return
            if self._error is None:
                try:
                    self._write(*item[0], **item[1])
                except BaseException as e:  # raised in the caller's thread at its next put or at the end
                    self._error = e

    def put(self, *args, **kwargs) -> None:
        """Queue one write (blocks while ``depth`` writes are waiting); raises a write's error."""
        while True:
            if self._error is not None:
                raise self._error
            try:
                self._q.put((args, kwargs), timeout=_POLL_S)
                return
            except queue.Full:
                continue

    def __enter__(self) -> WriteBehind:
        self._thread.start()
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            self._stop.set()
            while True:  # drop what waits, then let the thread see the end
                try:
                    self._q.get_nowait()
                except queue.Empty:
                    break
        self._q.put(_END)
        self._thread.join()
        if exc_type is None and self._error is not None:
            raise self._error
