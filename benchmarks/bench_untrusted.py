"""Oversized images are refused before decoding: time and peak memory, each in a fresh process.

    python benchmarks/bench_untrusted.py [--side 12000] [--runs 3]
    python benchmarks/bench_untrusted.py --resources [NAME ...]

``--resources`` runs the hostile small files of ``tests/fuzz/resource_cases.py`` (the
table and variants) as real commands, each in a child capped in address space and wall
clock, and prints per case: the exit status, peak RSS (``os.wait4``), wall time, whether
anything was left behind, and the error line.

Writes a side × side black PNG (streamed: a few hundred KB on disk, side² × 3 bytes decoded)
and measures, in child processes:

- ``read_image`` refusing it: the time of the call itself and the process's peak RSS;
- the whole ``relightnet relight-image`` command refusing it (Python start, imports, refusal);
- the start-up alone (Python + torch + relightnet imports), which the command's time includes;
- for scale, ``read_image`` decoding a 4000² PNG that is under the limit.

Prints a table (medians over ``--runs``) for BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import struct
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CHILD = """
import json, resource, sys, time
from relightnet.checks import InputError
from relightnet.io import read_image
t = time.perf_counter()
try:
    read_image(sys.argv[1]); refused = False
except InputError as e:
    refused = True
dt = time.perf_counter() - t
print(json.dumps({"s": dt, "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "refused": refused}))
"""


def black_png(path: Path, side: int) -> None:
    """A side × side RGB PNG of zeros, compressed row by row (never held decoded in memory)."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    z, row, parts = zlib.compressobj(9), b"\x00" * (1 + 3 * side), []
    for _ in range(side):
        parts.append(z.compress(row))
    parts.append(z.flush())
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", side, side, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", b"".join(parts)) + chunk(b"IEND", b""))


def child_read(path: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", CHILD, str(path)], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def child_command(path: Path, out: Path) -> tuple[float, float, str]:
    """Wall time, peak RSS (MiB, of this process alone: ``os.wait4``) and the one-line error of the command."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    t = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "relightnet.cli", "relight-image", str(path), "--light", "studio",
                             "--out", str(out)], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err = proc.stderr.read()
    _, _, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t
    proc.returncode = 0  # reaped by wait4
    return wall, usage.ru_maxrss / 1024, err.strip().splitlines()[-1]


def child_import() -> float:
    """Wall time of a process that only starts Python and imports relightnet's CLI and readers."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import relightnet.cli, relightnet.io"], env=env, check=True)
    return time.perf_counter() - t


def resources(names: list[str]) -> None:
    """The table of the resource cases (see the module docstring)."""
    sys.path.insert(0, str(ROOT / "tests" / "fuzz"))
    import resource_cases as rc

    print(f"budget: peak RSS <= {rc.RSS_BUDGET >> 20} MiB; child capped at {rc.AS_CAP >> 30} GiB address space "
          f"and {rc.WALL_CAP:.0f} s")
    print("| case | file | command | exit | peak RSS | wall | left behind | result |")
    print("|---|---|---|---|---|---|---|---|")
    for name in names or list(rc.CASES):
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            case = rc.CASES[name](folder)
            size = sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())
            res = rc.run_capped(case, folder)
            wrong = ""
            if case.check is not None and not res.timed_out and res.rc in (0, 1):  # the result itself
                try:
                    case.check(folder)
                except AssertionError as e:
                    wrong = f"; WRONG: {e}"
        lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
        line = (lines[-1] if lines else "").replace("|", "/")
        line = line if len(line) <= 110 else line[:107] + "..."
        status = "timed out" if res.timed_out else str(res.rc)
        command = next(a for a in case.argv if not a.startswith("-"))
        print(f"| {name} | {size / 1e3:,.0f} KB | {command} | {status} | {res.rss / 2**20:,.0f} MiB | "
              f"{res.wall:.1f} s | {', '.join(res.leftovers) or 'nothing'} | "
              f"{line if res.rc else 'ok: ' + ', '.join(case.outputs[:1])}{wrong} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--side", type=int, default=12000)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--resources", nargs="*", default=None, metavar="NAME")
    args = ap.parse_args()
    if args.resources is not None:
        resources(args.resources)
        return
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        big, small = tmp / "big.png", tmp / "small.png"
        black_png(big, args.side)
        black_png(small, 4000)
        size = big.stat().st_size
        reads = [child_read(big) for _ in range(args.runs)]
        cmds = [child_command(big, tmp / "out.png") for _ in range(args.runs)]
        smalls = [child_read(small) for _ in range(args.runs)]
        imports = [child_import() for _ in range(args.runs)]
    med = statistics.median
    print(f"{args.side}x{args.side} black PNG, {size / 1e3:.0f} KB on disk; medians of {args.runs} runs")
    print("| what | refused | call time | process wall | peak RSS |")
    print("|---|---|---|---|---|")
    print(f"| read_image({args.side}² PNG) | {all(r['refused'] for r in reads)} | "
          f"{med(r['s'] for r in reads) * 1e3:.1f} ms | | {med(r['rss_mb'] for r in reads):.0f} MiB |")
    print(f"| relightnet relight-image ({args.side}² PNG) | {all('above the limit' in c[2] for c in cmds)} | | "
          f"{med(c[0] for c in cmds):.2f} s | {max(c[1] for c in cmds):.0f} MiB |")
    print(f"| python -c 'import relightnet.cli, relightnet.io' (start-up alone) | | | "
          f"{med(imports):.2f} s | |")
    print(f"| read_image(4000² PNG, decoded) | {any(r['refused'] for r in smalls)} | "
          f"{med(r['s'] for r in smalls) * 1e3:.0f} ms | | {med(r['rss_mb'] for r in smalls):.0f} MiB |")
    print(f"\nerror line: {cmds[0][2]}")


if __name__ == "__main__":
    main()
