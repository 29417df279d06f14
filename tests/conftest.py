"""Fixtures shared by every test folder: the Anny cache location and one Anny model per session."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

# `make test` exports ANNY_CACHE_DIR; a bare `pytest` run uses the same repo cache.
os.environ.setdefault("ANNY_CACHE_DIR", str(Path(__file__).resolve().parents[1] / ".cache" / "anny"))
os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture(scope="session")
def anny_body():
    """The default AnnyBody (float32, feet on y = 0), built once per test session."""
    from relightnet.body import AnnyBody

    return AnnyBody()
