"""Reading ahead and writing behind in threads: the same items in order, errors where the caller is,
bounded queues, and threads that stop when the block is left."""

from __future__ import annotations

import threading
import time

import pytest

from relightnet.io.pipelined import ReadAhead, WriteBehind


def test_read_ahead_keeps_the_order_and_reads_ahead_of_the_caller():
    produced = []

    def items():
        for i in range(50):
            produced.append(i)
            yield i

    with ReadAhead(items(), depth=3) as ahead:
        first = next(ahead)
        time.sleep(0.2)  # the thread fills the queue meanwhile, then waits: at most depth + 1 ahead
        assert first == 0 and 2 <= len(produced) <= 5
        assert [first, *ahead] == list(range(50))
        with pytest.raises(StopIteration):
            next(ahead)


def test_an_error_in_the_source_reaches_the_caller_after_the_items_before_it():
    def items():
        yield 1
        yield 2
        raise ValueError("frame 2 is damaged")

    got = []
    with pytest.raises(ValueError, match="frame 2 is damaged"), ReadAhead(items()) as ahead:
        got.extend(ahead)
    assert got == [1, 2]


def test_leaving_early_stops_the_thread_and_closes_the_source():
    closed = threading.Event()

    def items():
        try:
            i = 0
            while True:
                yield i
                i += 1
        finally:
            closed.set()

    with ReadAhead(items(), depth=2, name="test-ahead") as ahead:
        for x in ahead:
            if x == 3:
                break
    assert closed.wait(2) and not any(t.name == "test-ahead" for t in threading.enumerate())


def test_write_behind_writes_everything_in_order_before_the_block_ends():
    written = []

    def write(x, time=None):
        written.append((x, time))

    with WriteBehind(write, depth=2) as behind:
        for i in range(40):
            behind.put(i, time=i / 10)
    assert written == [(i, i / 10) for i in range(40)]


def test_a_write_error_is_raised_to_the_caller_and_later_writes_are_not_made():
    written = []

    def write(x):
        if x == 5:
            raise OSError("disk full")
        written.append(x)

    with pytest.raises(OSError, match="disk full"), WriteBehind(write, depth=1) as behind:
        for i in range(100):
            behind.put(i)
    assert written == [0, 1, 2, 3, 4]


def test_an_error_in_the_caller_drops_the_waiting_writes():
    started, release, written = threading.Event(), threading.Event(), []

    def write(x):
        started.set()
        release.wait(2)
        time.sleep(0.2)  # each write is slow: the caller's error comes while the first is being made
        written.append(x)

    with pytest.raises(RuntimeError, match="caller failed"), WriteBehind(write, depth=4, name="test-behind") as b:
        for i in range(4):
            b.put(i)
        started.wait(2)
        release.set()
        raise RuntimeError("caller failed")
    assert written[:1] == [0] and len(written) <= 2 and not any(t.name == "test-behind" for t in threading.enumerate())


def test_depth_must_be_positive():
    with pytest.raises(ValueError, match="depth"):
        ReadAhead([], depth=0)
    with pytest.raises(ValueError, match="depth"):
        WriteBehind(print, depth=0)
