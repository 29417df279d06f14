import torch

from relightnet.fit import FIT_BONES


def test_fast_points_equal_full_mesh(fit_body):
    g = torch.Generator().manual_seed(0)
    sub = 0.3 * torch.randn(3, len(FIT_BONES), 3, generator=g)
    trans = torch.randn(3, 3, generator=g)
    phen = fit_body.body.phenotype_tensor({"height": 0.7, "weight": 0.2, "proportions": 0.8})
    with torch.no_grad():
        pts, sil, out = fit_body(sub, trans, phen)
        pts2, sil2 = fit_body.points(sub, trans, fit_body.rest(phen))
    # the same float32 sums in another order: a few ulps of metres-sized values
    torch.testing.assert_close(pts2, pts, atol=2e-5, rtol=0)
    torch.testing.assert_close(sil2, sil, atol=2e-5, rtol=0)


def test_fast_points_are_differentiable_in_shape(fit_body):
    from relightnet.fit import phenotype_from_free

    base = fit_body.body.phenotype_tensor(None)[0]
    free = torch.zeros(3, requires_grad=True)
    rest = fit_body.rest(phenotype_from_free(free, base))
    pts, _ = fit_body.points(torch.zeros(1, len(FIT_BONES), 3), torch.zeros(1, 3), rest)
    height = pts[0, 0, 1] - pts[0, 29, 1]  # nose above heel
    height.backward()
    assert float(free.grad[0]) > 0  # "height" makes the body taller
