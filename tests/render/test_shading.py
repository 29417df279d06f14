import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.render.shading import Shade, composite, shade, shading
from relightnet.sh import irradiance, sh_basis


def _normals(n, seed=0):
    g = torch.Generator().manual_seed(seed)
    return torch.nn.functional.normalize(torch.randn(n, 3, generator=g, dtype=torch.float64), dim=-1)


def test_unoccluded_closed_form_shading_equals_irradiance():
    # T_k = A_l Y_k(n) makes T.L the irradiance (the closed form of docs/design.md).
    n = _normals(37)
    a = torch.tensor([3.141592653589793] + [2.0943951023931953] * 3 + [0.7853981633974483] * 5, dtype=n.dtype)
    T = sh_basis(n, 2) * a
    L = torch.randn(9, 3, dtype=n.dtype)
    torch.testing.assert_close(shading(T, L), irradiance(L, n))
    alb = torch.rand(37, 3, dtype=n.dtype)
    torch.testing.assert_close(shade(alb, T, L), alb * irradiance(L, n))


@pytest.mark.parametrize("n", [1, 4, 7, 4096 + 3])
def test_grouped_gemm_matches_plain_matmul(n):
    T = torch.randn(n, 9)
    L = torch.randn(9, 3)
    torch.testing.assert_close(shading(T, L), T @ L, atol=1e-5, rtol=1e-5)


def test_image_batch_light_and_per_channel_transport():
    T = torch.randn(2, 5, 6, 9)
    A = torch.rand(2, 5, 6, 3)
    L = torch.randn(2, 9, 3)
    out = shade(A, T, L)
    torch.testing.assert_close(out[1], A[1] * (T[1] @ L[1]), atol=1e-5, rtol=1e-5)
    Tc = torch.randn(4, 9, 3)
    torch.testing.assert_close(shading(Tc, L[0]), torch.einsum("vkc,kc->vc", Tc, L[0]))
    torch.testing.assert_close(Shade(L[0])(A[0], T[0]), shade(A[0], T[0], L[0]))


def test_gradients_flow():
    T = torch.randn(3, 9, requires_grad=True)
    A = torch.rand(3, 3, requires_grad=True)
    L = torch.randn(9, 3, requires_grad=True)
    shade(A, T, L).sum().backward()
    assert T.grad is not None and A.grad is not None and L.grad is not None


def test_composite():
    fg = torch.ones(1, 2, 2, 3)
    bg = torch.zeros(2, 2, 3)
    alpha = torch.tensor([[[1.0, 0.0], [0.5, 0.0]]])
    out = composite(fg, alpha, bg)
    assert out[0, 0, 0].tolist() == [1, 1, 1] and out[0, 0, 1].tolist() == [0, 0, 0]
    assert out[0, 1, 0].tolist() == [0.5, 0.5, 0.5]


def test_bad_inputs():
    with pytest.raises(ShapeError, match="light: expected K"):
        shading(torch.randn(4, 8), torch.randn(8, 3))
    with pytest.raises(ShapeError, match="transport: expected"):
        shading(torch.randn(4, 4), torch.randn(9, 3))
    with pytest.raises(InputError, match="light: contains NaN"):
        shade(torch.rand(4, 3), torch.randn(4, 9), torch.full((9, 3), float("nan")))
    with pytest.raises(ShapeError, match="alpha"):
        composite(torch.ones(1, 2, 2, 3), torch.ones(1, 3, 2), torch.zeros(2, 2, 3))


def test_shade_and_composite_on_device_match_float64_cpu(device, dtype):
    g = torch.Generator().manual_seed(5)
    alb, T = torch.rand(2, 6, 5, 3, generator=g, dtype=torch.float64), torch.randn(2, 6, 5, 9, generator=g,
                                                                                  dtype=torch.float64)
    L, bg = torch.randn(9, 3, generator=g, dtype=torch.float64), torch.rand(6, 5, 3, generator=g, dtype=torch.float64)
    alpha = torch.rand(2, 6, 5, generator=g, dtype=torch.float64)
    ref = composite(shade(alb, T, L), alpha, bg)
    on = [x.to(device, dtype) for x in (alb, T, L, alpha, bg)]
    out = composite(shade(*on[:3]), on[3], on[4])
    assert out.device.type == device.type and out.dtype == dtype and out.shape == (2, 6, 5, 3)
    tol = 1e-5 if dtype == torch.float32 else 1e-12
    torch.testing.assert_close(out.cpu().double(), ref, atol=tol, rtol=tol)


def test_shade_and_composite_gradcheck(device):
    g = torch.Generator().manual_seed(6)
    args = [torch.rand(1, 3, 2, 3, generator=g, dtype=torch.float64), torch.randn(1, 3, 2, 9, generator=g,
                                                                               dtype=torch.float64),
            torch.randn(9, 3, generator=g, dtype=torch.float64), torch.rand(1, 3, 2, generator=g, dtype=torch.float64),
            torch.rand(3, 2, 3, generator=g, dtype=torch.float64)]
    args = [a.to(device).requires_grad_(True) for a in args]
    assert torch.autograd.gradcheck(lambda a, t, light, al, bg: composite(shade(a, t, light), al, bg), args)
    # the per-channel transport of coloured interreflection (..., K, 3), and a batched light
    t3 = torch.randn(2, 4, 9, 3, generator=g, dtype=torch.float64).to(device).requires_grad_(True)
    lb = torch.randn(2, 9, 3, generator=g, dtype=torch.float64).to(device).requires_grad_(True)
    assert torch.autograd.gradcheck(lambda t, light: shading(t, light), (t3, lb))


@pytest.mark.parametrize("batched", [False, True])
def test_shading_of_a_cnn_map_equals_the_per_pixel_sum(batched):
    """A channels-last view of (B, K, H, W) memory goes through the transposed product: same values."""
    from relightnet.raster import to_channels_last

    g = torch.Generator().manual_seed(1)
    T = torch.randn(3, 9, 6, 5, generator=g, dtype=torch.float64)
    L = torch.randn(3, 9, 3, generator=g, dtype=torch.float64) if batched else torch.randn(9, 3, generator=g,
                                                                                         dtype=torch.float64)
    want = torch.einsum("bkhw,bkc->bhwc", T, L) if batched else torch.einsum("bkhw,kc->bhwc", T, L)
    torch.testing.assert_close(shading(to_channels_last(T), L), want)
    with pytest.raises(ValueError, match="leading dim"):
        shading(to_channels_last(T), torch.randn(2, 9, 3, dtype=torch.float64))


def test_shade_with_shading_returns_both():
    A, T, L = torch.rand(4, 3), torch.randn(4, 9), torch.randn(9, 3)
    rad, S = shade(A, T, L, with_shading=True)
    torch.testing.assert_close(S, shading(T, L))
    torch.testing.assert_close(rad, A * S)


def test_composite_covered_equals_composite_with_binary_alpha():
    from relightnet.render.shading import composite_covered

    g = torch.Generator().manual_seed(2)
    bg = torch.randint(0, 256, (5, 4, 3), generator=g, dtype=torch.uint8)
    fg = torch.randint(0, 256, (1, 5, 4, 3), generator=g, dtype=torch.uint8)
    alpha = (torch.rand(1, 5, 4, generator=g) > 0.5).float()
    pix = torch.nonzero(alpha.flatten()).flatten()
    got = composite_covered(fg.reshape(-1, 3)[pix], pix, bg)
    want = composite(fg.float(), alpha, bg.float())[0].to(torch.uint8)
    assert torch.equal(got, want)
    assert not torch.equal(got, bg) or pix.numel() == 0
    with pytest.raises(ShapeError, match="fg"):
        composite_covered(torch.zeros(2, 3, dtype=torch.uint8), torch.tensor([0]), bg)
