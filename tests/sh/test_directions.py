import math

import pytest
import torch

from relightnet.sh import directions_to_latlong, fibonacci_sphere, latlong_directions
from relightnet.sh.directions import fibonacci_hemisphere, random_fibonacci_sphere


def test_fibonacci_sets():
    d, w = fibonacci_sphere(500)
    assert d.shape == (500, 3) and w.sum().item() == pytest.approx(4 * math.pi)
    torch.testing.assert_close(d.norm(dim=-1), torch.ones(500))
    assert d.mean(0).abs().max() < 0.01  # balanced
    h, hw = fibonacci_hemisphere(300)
    assert (h[:, 2] > 0).all() and hw.sum().item() == pytest.approx(2 * math.pi)


def test_random_fibonacci_is_seeded():
    a, _ = random_fibonacci_sphere(64, torch.Generator().manual_seed(1))
    b, _ = random_fibonacci_sphere(64, torch.Generator().manual_seed(1))
    c, _ = random_fibonacci_sphere(64, torch.Generator().manual_seed(2))
    torch.testing.assert_close(a, b)
    assert not torch.allclose(a, c)
    torch.testing.assert_close(a.norm(dim=-1), torch.ones(64))


def test_latlong_solid_angles_and_inverse():
    d, sa = latlong_directions(32, 64, torch.float64)
    assert sa.sum().item() == pytest.approx(4 * math.pi)
    assert d[0, 32, 1] > 0.99  # top row looks up
    torch.testing.assert_close(d[16, 32], torch.tensor([0.0, 0.0, -1.0], dtype=torch.float64), atol=0.06, rtol=0)
    uv = directions_to_latlong(d, 32, 64)
    v, u = torch.meshgrid(torch.arange(32.0), torch.arange(64.0), indexing="ij")
    torch.testing.assert_close(uv, torch.stack([u + 0.5, v + 0.5], -1).double(), atol=1e-9, rtol=0)


def test_bad_counts():
    with pytest.raises(ValueError, match="n: expected"):
        fibonacci_sphere(0)
