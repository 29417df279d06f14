"""The light solve: exact with exact maps, differentiable, regularised toward its prior, pooled over frames."""

import pytest
import torch

from relightnet.light import directional_light
from relightnet.model.network import NetConfig, RelightNet, normalize_input
from relightnet.sh import irradiance
from relightnet.sh.light_solve import Evidence, light_evidence, pool_evidence, solve_light, spd_solve


def _scene(b=2, k=9, h=24, w=20, seed=0):
    g = torch.Generator().manual_seed(seed)
    T = torch.randn(b, k, h, w, generator=g)
    A = torch.rand(b, 3, h, w, generator=g) * 0.8 + 0.1
    L = torch.randn(b, k, 3, generator=g)
    return T, A, L, A * torch.einsum("bkhw,bkc->bchw", T, L)


def test_spd_solve_matches_linalg():
    g = torch.Generator().manual_seed(1)
    A = torch.randn(3, 4, 9, 9, generator=g, dtype=torch.float64)
    A = A @ A.transpose(-1, -2) + 0.1 * torch.eye(9, dtype=torch.float64)
    b = torch.randn(3, 4, 9, generator=g, dtype=torch.float64)
    assert torch.allclose(spd_solve(A, b), torch.linalg.solve(A, b), atol=1e-10)


def test_exact_maps_recover_the_light():
    T, A, L, I = _scene()
    ev = light_evidence(I, A, T, torch.ones(2, 1, 24, 20))
    assert ev.M.shape == (2, 3, 9, 9) and ev.r.shape == (2, 3, 9)
    assert torch.allclose(solve_light(ev, None, 1e-7), L, atol=1e-3)


def test_weights_select_pixels():
    """Pixels of zero weight do not count: corrupting them leaves the solve unchanged."""
    T, A, L, I = _scene(b=1)
    w = torch.ones(1, 1, 24, 20)
    w[..., :8, :] = 0
    bad = I.clone()
    bad[..., :8, :] = 5.0
    a, b = (solve_light(light_evidence(x, A, T, w), None, 1e-6) for x in (I, bad))
    assert torch.allclose(a, b, atol=1e-5)


def test_regularisation_pulls_toward_the_prior():
    T, A, L, I = _scene(b=1)
    ev = light_evidence(I, A, T, torch.ones(1, 1, 24, 20))
    prior = torch.zeros_like(L) + 0.3
    weak, strong = solve_light(ev, prior, 1e-6), solve_light(ev, prior, 1e4)
    assert (weak - L).abs().max() < 1e-2
    assert (strong - prior).abs().max() < 1e-2


def test_exposure_does_not_change_the_balance():
    """λ is relative to the evidence's scale: a brighter image gives the same light up to that scale."""
    T, A, L, I = _scene(b=1)
    prior = torch.randn_like(L)
    ones = torch.ones(1, 1, 24, 20)
    a = solve_light(light_evidence(I, A, T, ones), prior, 0.5)
    b = solve_light(light_evidence(4 * I, A, T, ones), 4 * prior, 0.5)
    assert torch.allclose(4 * a, b, rtol=1e-4, atol=1e-4)


def test_gradients_flow_to_every_map():
    T, A, L, I = _scene(b=1)
    T, A = T.requires_grad_(), A.requires_grad_()
    w = torch.ones(1, 1, 24, 20, requires_grad=True)
    solve_light(light_evidence(I, A, T, w), None, 1e-2).square().sum().backward()
    assert all(x.grad is not None and torch.isfinite(x.grad).all() and x.grad.abs().sum() > 0 for x in (T, A, w))


def test_pooling_frames_of_one_light():
    """Frames that each see half of the pixels pool into the full solve."""
    T, A, L, I = _scene(b=1)
    top, bottom = torch.zeros(1, 1, 24, 20), torch.zeros(1, 1, 24, 20)
    top[..., :12, :], bottom[..., 12:, :] = 1, 1
    e1, e2 = light_evidence(I, A, T, top), light_evidence(I, A, T, bottom)
    both = Evidence(torch.cat([e1.M, e2.M]), torch.cat([e1.r, e2.r]))
    pooled = pool_evidence(both, torch.ones(1, 2))
    full = light_evidence(I, A, T, torch.ones(1, 1, 24, 20))
    assert torch.allclose(solve_light(pooled, None, 1e-3), solve_light(full, None, 1e-3), atol=1e-4)


@pytest.mark.parametrize("mode", ["head", "solve", "hybrid"])
def test_network_modes(mode):
    torch.manual_seed(0)
    net = RelightNet(NetConfig(width=8, max_width=32, light_hidden=16, levels=2, light_mode=mode))
    x = normalize_input(torch.rand(2, 3, 32, 32), torch.ones(2, 1, 32, 32))
    p = net(x)
    assert p.light.shape == (2, 9, 3) and p.transport.shape == (2, 9, 32, 32)
    assert (p.evidence is None) == (mode == "head")
    assert (p.light_head is None) == (mode != "hybrid")  # head: the light is the head itself
    if mode != "head":  # the returned light is the solve of the returned evidence
        assert torch.allclose(p.light, solve_light(p.evidence, p.light_head, net.config.solve_reg), atol=1e-5)
    with torch.autocast("cpu", dtype=torch.bfloat16):
        q = net(x)
    if mode != "head":
        assert q.light.dtype == torch.float32


def front_of_sphere(h=32, max_angle_deg=None):
    """Exact float32 maps of the front of a sphere (normals up to 63° from the view, or within
    ``max_angle_deg``: a narrower cone is worse conditioned), one albedo, the image they render.
    Also the cases of ``benchmarks/bench_light_precision.py``.

    Returns:
        ``(image (1, 3, h, h), albedo (1, 3, h, h), transport (1, 9, h, h), inside (1, 1, h, h), light (9, 3))``.
    """
    from relightnet.sh import sh_basis
    from relightnet.sh.irradiance import cosine_lobe_per_coeff

    ys, xs = torch.meshgrid(torch.linspace(-0.9, 0.9, h), torch.linspace(-0.9, 0.9, h), indexing="ij")
    inside = (xs**2 + ys**2 < 0.8).float()[None, None]
    if max_angle_deg is not None:
        scale = torch.sin(torch.deg2rad(torch.tensor(float(max_angle_deg)))) / 0.8**0.5
        xs, ys = xs * scale, ys * scale
    n = torch.stack([(1 - xs**2 - ys**2).clamp_min(0.05).sqrt(), xs, -ys], -1)
    n = n / n.norm(dim=-1, keepdim=True)
    light = directional_light([0.6, 0.5, 0.62], [0.9, 0.8, 0.7], sharpness=5.0) + 0.1 * torch.eye(9, 3)[:, :1] * 3
    T = (sh_basis(n, 2) * cosine_lobe_per_coeff(2)).permute(2, 0, 1)[None]
    albedo = torch.full((1, 3, h, h), 0.5)
    image = albedo * irradiance(light, n).permute(2, 0, 1)[None]
    return image, albedo, T, inside, light


def test_solve_network_reads_the_image_it_was_given():
    """The network's solve undoes normalize_input: given exact maps, it recovers the light that
    rendered the (sRGB, masked) input image to 1e-4 on any CPU.

    A front view's normals make the normal equations ill-conditioned (cond(M) ≈ 1.6e4, checked
    below). Solved in float64 the error is the regulariser's bias, ≤ λ·cond(M)·max|L| ≈ 3e-5 at
    λ = 1e-9, plus the float32 inputs' rounding (≈ 2⁻²⁴ relative, through the sRGB round trip)
    amplified by √cond(M) ≈ 130 for a zero-residual least squares: ≈ 1e-5. Neither depends on the
    order in which a CPU's kernels sum the pixels (the float32 solve erred by 2e-3 here and by
    1e-2 on an AVX2-only CPU)."""
    from relightnet.color import linear_to_srgb

    net = RelightNet(NetConfig(width=8, max_width=32, light_hidden=16, levels=2, light_mode="solve", solve_reg=1e-9))
    image, albedo, T, inside, light = front_of_sphere()
    cond = torch.linalg.cond(light_evidence(image, albedo, T, inside).M[0, 0])
    assert 1e3 < cond < 1e5
    assert 0 < image.min() and image.max() < 1
    x = normalize_input(linear_to_srgb(image), inside)
    p = net._solve(x, albedo, T, torch.zeros(1, 1, 32, 32), None, None)
    assert p.evidence.M.dtype == torch.float64 and p.light.dtype == torch.float32
    assert (p.light[0] - light).abs().max() <= 1e-4
    assert torch.allclose(p.confidence, inside, atol=1e-4)  # softplus(0.5413) = 1


@pytest.mark.parametrize("cone", [None, 60.0, 30.0])
def test_the_order_of_summation_does_not_change_the_light(cone):
    """Another CPU sums the pixels in another order (its matmul kernel's blocking); a permutation of
    the pixels does the same here. In float64 the sums differ by at most P·ε₆₄ relative, and the
    solve amplifies that by at most cond(M): the light moves by ≤ cond(M)·P·ε₆₄·max|L| (≈ 1e-8 for
    the front view, 5e-6 for the 30° cone, cond ≈ 1e7), where the float32 solve moved by 3e-3 and 0.5."""
    image, albedo, T, inside, light = front_of_sphere(max_angle_deg=cone)
    ev = light_evidence(image, albedo, T, inside)
    M = ev.M[0, 0]
    cond = float(torch.linalg.cond(M + 1e-6 * M.diagonal().mean() * torch.eye(9, dtype=torch.float64)))
    p = image.shape[-1] * image.shape[-2]
    tol = cond * p * torch.finfo(torch.float64).eps * float(light.abs().max())
    base = solve_light(ev, None, 1e-6)
    g = torch.Generator().manual_seed(3)
    for _ in range(3):
        perm = torch.randperm(p, generator=g)
        shuffled = [x.flatten(2)[..., perm].reshape(x.shape) for x in (image, albedo, T, inside)]
        assert (solve_light(light_evidence(*shuffled), None, 1e-6) - base).abs().max() <= tol


def test_pooled_evidence_stays_float64():
    T, A, L, I = _scene(b=1)
    ev = light_evidence(I, A, T, torch.ones(1, 1, 24, 20))
    pooled = pool_evidence(Evidence(ev.M.float(), ev.r.float()), torch.ones(1, 1))
    assert ev.M.dtype == ev.r.dtype == pooled.M.dtype == pooled.r.dtype == torch.float64


def test_spd_solve_scales_rows_without_changing_the_answer():
    """Equilibration: rows of very unequal scale (1e-6 … 1e6) are solved as well as equal ones."""
    g = torch.Generator().manual_seed(2)
    B = torch.randn(9, 9, generator=g, dtype=torch.float64)
    A = B @ B.T + 0.5 * torch.eye(9, dtype=torch.float64)
    D = torch.diag(torch.logspace(-3, 3, 9, dtype=torch.float64))
    x = torch.randn(9, generator=g, dtype=torch.float64)
    As = D @ A @ D
    assert torch.allclose(spd_solve(As, As @ x), x, rtol=1e-8, atol=1e-8 * float(x.abs().max()))
