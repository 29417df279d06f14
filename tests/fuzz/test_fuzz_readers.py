"""Fuzzing every reader: seeded malformed files end in InputError, never a traceback, a hang or a crash.

The corpus (tests/fuzz/corpus_*.py, mutations.py, payloads.py) runs in a child process
(runner.py) with a watchdog per case, so a crash or a hang in C code (FFmpeg, ONNX Runtime,
torch's zip reader) fails the reader it happened in instead of the test session; the child is
restarted for the readers after it.
"""

from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # the whole malformed-file corpus in a watched child process

RUNNER = Path(__file__).with_name("runner.py")
READERS = ("light-npz", "light-json", "light-npy", "light-exr", "light-hdr", "motion-npz", "motion-pkl", "smpl-npz",
           "smpl-pkl", "image", "mask", "video", "synth-config", "train-config", "shard", "manifest", "checkpoint",
           "onnx")
#: Cases per reader (plus 40 payloads for each pickle reader); the seed fixes every case.
CASES = 200
SEED = 0
CASE_TIMEOUT = 120  # seconds: a hang, not a slow case on a busy machine


@pytest.fixture(scope="module")
def fuzz(tmp_path_factory):
    work = tmp_path_factory.mktemp("fuzz")
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))
    remaining, crashes = list(READERS), {}
    while remaining:
        proc = subprocess.run([sys.executable, str(RUNNER), str(work), *remaining, "--cases", str(CASES),
                               "--seed", str(SEED), "--timeout", str(CASE_TIMEOUT)],
                              env=env, capture_output=True, text=True)
        done = {json.loads(line)["reader"] for line in (work / "results.jsonl").read_text().splitlines()} \
            if (work / "results.jsonl").exists() else set()
        if proc.returncode == 0:
            break
        started = [line.split() for line in (work / "progress.txt").read_text().splitlines()]
        reader, case, kind = started[-1][1:4]
        crashes[reader] = f"case {case} ({kind}) ended the process (rc {proc.returncode}): {proc.stderr[-800:]}"
        remaining = [n for n in remaining if n not in done and n != reader]
    results = {}
    for line in (work / "results.jsonl").read_text().splitlines():
        r = json.loads(line)
        results[r["reader"]] = r
    return results, crashes


@pytest.mark.parametrize("reader", READERS)
def test_every_malformed_file_ends_in_input_error(fuzz, reader):
    results, crashes = fuzz
    assert reader not in crashes, crashes[reader]
    r = results[reader]
    assert r["cases"] >= CASES
    assert r["failures"] == [], "\n".join(f"{f['kind']}: {f['error']} at {f['where']} ({f['file']})"
                                          for f in r["failures"][:8])
    # The corpus is really malformed: many cases are refused (mutations that keep a file valid pass;
    # a video decoder skips a damaged frame).
    assert r["input_error"] >= r["cases"] // 5


def test_pickle_payloads_create_nothing(fuzz):
    results, _ = fuzz
    for reader in ("motion-pkl", "smpl-pkl", "checkpoint"):
        r = results[reader]
        assert r["payloads"] == 40 and r["executed"] == 0, r


def test_the_payloads_are_real(tmp_path):
    """The same payloads do create their file under an unrestricted unpickler (so 0 above means something)."""
    sys.path.insert(0, str(Path(__file__).parent))
    try:
        import payloads
    finally:
        sys.path.pop(0)
    payloads.MARKERS = tmp_path
    cases = dict(payloads.payloads("pickle"))
    pickle.loads(cases["builtins.open#0"])
    pickle.loads(cases["pathlib.Path.touch#2"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["made-open", "made-touch"]
