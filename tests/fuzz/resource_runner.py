"""The capped child process the resource cases run in (``resource_cases.py``, the test and the benchmark).

:func:`run_capped` runs a ``relightnet`` command in a child process that caps its own address
space (``RLIMIT_AS``) and is killed after a wall-clock cap, with its own ``TMPDIR``, and reports
its exit status, stderr, peak RSS (its own ``VmHWM``) and what it left behind.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: The memory budget every case must stay within (peak RSS of the command's process).
RSS_BUDGET = 2 << 30
#: Address-space cap of the child: it cannot take the machine's memory even if a case regresses.
AS_CAP = 4 << 30
#: Wall-clock cap of the child (a hang, not a slow run on a loaded machine).
WALL_CAP = 120.0
#: Files a third-party library writes in TMPDIR on import, not relightnet: onnxruntime's native
#: library keeps a 51-byte ``$TMPDIR/.ses`` (one fixed name, rewritten, never more than one).
THIRD_PARTY_TMP = ("_tmp/.ses",)


@dataclass
class Case:
    """A command over generated files: ``argv`` after ``relightnet``; ``names``: the file its error must name."""

    argv: list[str]
    names: str
    expect: str = "error"  # "error": exit 1 with one line naming ``names``; "ok": exit 0; "any": either
    outputs: tuple[str, ...] = ()  # files the command may leave (relative to the case folder)
    #: called with the case folder after the other assertions: raises AssertionError if the result is wrong
    check: Callable[[Path], None] | None = None


@dataclass
class Result:
    rc: int
    stderr: str
    rss: int  # bytes
    wall: float
    timed_out: bool
    leftovers: list[str]


#: The child: caps its own address space, runs ``relightnet`` as ``python -m relightnet.cli``
#: would, and at exit records its peak RSS (``VmHWM`` of its own memory map). ``ru_maxrss``
#: from ``wait4`` would also count the parent's RSS at fork time (Linux carries the old memory
#: map's high-water mark across ``exec``), which inside a test session is hundreds of MB.
_CHILD = """
import atexit, resource, runpy, sys
cap, out = int(sys.argv[1]), sys.argv[2]
resource.setrlimit(resource.RLIMIT_AS, (cap, cap))

def _peak():
    with open("/proc/self/status") as f:
        kb = next(line.split()[1] for line in f if line.startswith("VmHWM:"))
    with open(out, "w") as f:
        f.write(kb)

atexit.register(_peak)
sys.argv = ["relightnet", *sys.argv[3:]]
runpy.run_module("relightnet.cli", run_name="__main__", alter_sys=True)
"""


def _vm_hwm(pid: int) -> int | None:
    """A live process's peak RSS in bytes (``VmHWM``), or None if it cannot be read."""
    try:
        with open(f"/proc/{pid}/status") as f:
            return int(next(line.split()[1] for line in f if line.startswith("VmHWM:"))) * 1024
    except (OSError, StopIteration, ValueError):
        return None


def run_capped(case: Case, folder: Path, wall: float = WALL_CAP) -> Result:
    """Run ``relightnet *case.argv`` in ``folder`` capped; what it left in ``folder`` and its TMPDIR."""
    tmp = folder / "_tmp"
    tmp.mkdir(exist_ok=True)
    before = {p for p in folder.rglob("*") if tmp not in p.parents}
    env = dict(os.environ, PYTHONPATH=str(ROOT), TMPDIR=str(tmp), OMP_NUM_THREADS="1")
    peak_file = folder / "_peak"

    with open(folder / "_stderr", "w+b") as err:
        t = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-c", _CHILD, str(AS_CAP), str(peak_file), *case.argv], cwd=folder,
                                env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=err)
        timed_out, hwm = False, None
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.perf_counter() - t > wall:
                timed_out = True
                hwm = _vm_hwm(proc.pid)  # read while it lives: a killed child writes no peak file
                proc.kill()
                _, status, usage = os.wait4(proc.pid, 0)
                break
            time.sleep(0.05)
        proc.returncode = os.waitstatus_to_exitcode(status)
        elapsed = time.perf_counter() - t
        err.seek(0)
        stderr = err.read().decode("utf-8", "replace")
    try:
        rss = int(peak_file.read_text()) * 1024
        peak_file.unlink()
    except (OSError, ValueError):  # killed before its exit handler ran: its high-water mark read before the kill
        rss = hwm if timed_out and hwm is not None else usage.ru_maxrss * 1024
    left = sorted(str(p.relative_to(folder)) for p in folder.rglob("*")
                  if p not in before and p.name != "_stderr" and p != tmp
                  and str(p.relative_to(folder)) not in case.outputs + THIRD_PARTY_TMP and p.is_file())
    return Result(proc.returncode, stderr, rss, elapsed, timed_out, left)
