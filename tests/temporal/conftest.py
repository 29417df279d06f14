"""Temporal-test fixtures."""

import pytest
import torch

from relightnet.light import preset_light


def step_seq(t_len=40, step=10, noise=0.0, seed=0):
    """(truth, noisy) (T, 9, 3): the studio light switching to sunset at ``step``, plus Gaussian noise."""
    a, b = preset_light("studio"), preset_light("sunset")
    truth = torch.stack([a if t < step else b for t in range(t_len)])
    g = torch.Generator().manual_seed(seed)
    return truth, truth + noise * torch.randn(truth.shape, generator=g)


def _poly_lights(t_len, degree, seed=0):
    """(T, 9, 3) lights whose every coefficient is a random polynomial of ``degree`` in t."""
    g = torch.Generator().manual_seed(seed)
    c = torch.randn(degree + 1, 9, 3, generator=g, dtype=torch.float64)
    t = torch.linspace(-1.3, 0.7, t_len, dtype=torch.float64)
    return sum(c[i] * t[:, None, None] ** i for i in range(degree + 1))


@pytest.fixture
def poly_lights():
    """``poly_lights(t_len, degree, seed=0)`` → (T, 9, 3) polynomial light sequences (float64)."""
    return _poly_lights
