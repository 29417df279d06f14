"""Pipeline-test fixtures: running a command in a child process and killing it mid-run."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest


def temp_files(folder: Path) -> list[Path]:
    """Hidden temporary files and staging folders (``.name.….tmp``) left in ``folder``."""
    return sorted(p for p in folder.iterdir() if p.name.startswith(".") and p.name.endswith(".tmp"))


@pytest.fixture
def kill_mid_run():
    """``kill_mid_run(argv, folder, ready)`` runs ``relightnet ARGV`` in a child process, SIGKILLs it
    as soon as ``ready(temp_files(folder))`` is true (it is writing), and returns the temporary
    files it left. Fails if the command ends before that."""

    def run(argv, folder: Path, ready=lambda temps: any(p.is_file() and p.stat().st_size for p in temps),
            timeout: float = 900.0) -> list[Path]:
        env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))
        child = subprocess.Popen([sys.executable, "-m", "relightnet.cli", "-q", *argv], env=env,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        end = time.monotonic() + timeout
        try:
            while child.poll() is None and time.monotonic() < end:
                if ready(temp_files(folder)):
                    child.send_signal(signal.SIGKILL)
                    child.wait()
                    return temp_files(folder)
                time.sleep(0.005)
        finally:
            if child.poll() is None:
                child.kill()
                child.wait()
        pytest.fail(f"relightnet {argv[0]} ended (rc {child.returncode}) before it could be killed mid-run: "
                    f"{child.stderr.read().decode()[-500:]}")

    return run
