"""Data-test fixtures."""

import pytest
import torch


@pytest.fixture(scope="module")
def one_thread():
    """torch on one thread for a module, as the generator's worker processes run (one sample per
    single-threaded worker; on a loaded 2-core machine intra-op threads make it ~8x slower, and
    clip_geometry reproduces the masks bit for bit only at the same thread count)."""
    n = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(n)
