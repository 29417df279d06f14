"""Seeded mutations of a valid file's bytes, the same for every run (tests/fuzz)."""

from __future__ import annotations

import random
import struct

#: Integers that break size fields: all ones, signed limits, powers of two, zero.
BIG = (0xFFFFFFFF, 0x7FFFFFFF, 0x80000000, 0x00010000, 0x0000FFFF, 0, 1 << 24)


def _truncate(b: bytes, r: random.Random) -> bytes:
    return b[: r.choice([0, 1, 4, 8, 16, r.randrange(len(b) + 1), r.randrange(len(b) + 1)])]


def _flip_bits(b: bytes, r: random.Random, head: int | None = None) -> bytes:
    out = bytearray(b)
    if not out:
        return b"\x00"
    span = min(len(out), head) if head else len(out)
    for _ in range(r.randint(1, 16)):
        out[r.randrange(span)] ^= 1 << r.randrange(8)
    return bytes(out)


def _big_int(b: bytes, r: random.Random) -> bytes:
    out = bytearray(b)
    if len(out) < 4:
        return b + struct.pack("<I", r.choice(BIG))
    at = r.randrange(min(len(out) - 3, r.choice([64, 512, len(out) - 3])))
    out[at:at + 4] = struct.pack(r.choice("<>") + "I", r.choice(BIG))
    return bytes(out)


def _chunk_ops(b: bytes, r: random.Random) -> bytes:
    if not b:
        return b"\xff" * r.randint(1, 64)
    i, j = sorted(r.randrange(len(b) + 1) for _ in range(2))
    op = r.randrange(4)
    if op == 0:  # delete
        return b[:i] + b[j:]
    if op == 1:  # duplicate
        return b[:j] + b[i:j] + b[j:]
    if op == 2:  # zero a run
        return b[:i] + bytes(j - i) + b[j:]
    return b + bytes(r.randrange(256) for _ in range(r.randint(1, 256)))  # trailing junk


def mutate(data: bytes, seed: int) -> tuple[str, bytes]:
    """One mutation of ``data`` chosen by ``seed``: (kind, bytes)."""
    r = random.Random(seed)
    kind = r.choice(("truncate", "bits", "header-bits", "big-int", "chunk", "chunk", "bits"))
    if kind == "truncate":
        return kind, _truncate(data, r)
    if kind == "bits":
        return kind, _flip_bits(data, r)
    if kind == "header-bits":
        return kind, _flip_bits(data, r, head=256)
    if kind == "big-int":
        return kind, _big_int(data, r)
    return kind, _chunk_ops(data, r)
