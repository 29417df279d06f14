"""torch_threads: the block runs on the given thread count, and the caller's count comes back."""

import pytest
import torch

from relightnet.checks import InputError
from relightnet.threads import torch_threads


@pytest.fixture
def two_threads():
    before = torch.get_num_threads()
    torch.set_num_threads(2)
    yield
    torch.set_num_threads(before)


def test_the_count_is_set_inside_and_restored_after(two_threads):
    with torch_threads(1):
        assert torch.get_num_threads() == 1
    assert torch.get_num_threads() == 2


def test_the_count_is_restored_when_the_block_raises(two_threads):
    with pytest.raises(KeyError), torch_threads(1):
        raise KeyError("inside")
    assert torch.get_num_threads() == 2


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2"])
def test_a_bad_count_is_refused_and_nothing_changes(two_threads, bad):
    with pytest.raises(InputError, match="threads: expected an integer >= 1"), torch_threads(bad):
        pass
    assert torch.get_num_threads() == 2
