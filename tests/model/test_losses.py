"""relightnet.model.losses: the masked image losses and the loss weights of the configs."""

import pytest
import torch

from relightnet.model.losses import LossWeights, masked_l1, total_variation


def test_masked_l1_counts_only_masked_pixels_and_channels():
    a, b = torch.zeros(1, 3, 2, 2), torch.zeros(1, 3, 2, 2)
    b[:, :, 0, 0] = 2.0
    b[:, :, 1, 1] = 100.0  # outside the mask
    mask = torch.tensor([[[[1.0, 1.0], [1.0, 0.0]]]])
    assert masked_l1(a, b, mask).item() == pytest.approx(2.0 * 3 / (3 * 3))
    assert masked_l1(a, b, torch.zeros_like(mask)).item() == 0  # empty mask: no division by zero


def test_total_variation_of_a_step_inside_and_across_the_mask():
    x = torch.zeros(1, 1, 4, 4)
    x[..., :, 2:] = 1.0  # a vertical edge between columns 1 and 2
    full = torch.ones(1, 1, 4, 4)
    assert total_variation(x, full).item() == pytest.approx(4 / 16)
    left = torch.zeros(1, 1, 4, 4)
    left[..., :, :2] = 1
    assert total_variation(x, left).item() == 0  # the edge lies outside the mask
    x.requires_grad_(True)
    total_variation(x, full).backward()
    assert x.grad.abs().sum() > 0


def test_loss_weights_defaults_and_dict():
    w = LossWeights(tv=0.1)
    d = w.to_dict()
    assert d["tv"] == 0.1 and d["transport"] == 1.0 and d["relit_novel"] == 0.0
    assert LossWeights(**d) == w
    with pytest.raises(TypeError):
        LossWeights(unknown=1.0)
