import torch

from relightnet.fit.body_model import FIT_BONES


def test_fast_points_equal_full_mesh(fit_body):
    """The reduced kinematics (:meth:`FitBody.points`) give the full mesh's points.

    Measured against the same body in float64: Anny's own float32 pass rounds along 100-bone
    chains (about 5e-5 m on AVX2 here), the reduced pass along at most 6 fitted bones and one
    68-term blend: its error is bounded by a few dozen float32 roundings of the largest coordinate.
    """
    from relightnet.body import AnnyBody
    from relightnet.fit import FitBody

    g = torch.Generator().manual_seed(0)
    sub = 0.3 * torch.randn(3, len(FIT_BONES), 3, generator=g)
    trans = torch.randn(3, 3, generator=g)
    phen = fit_body.body.phenotype_tensor({"height": 0.7, "weight": 0.2, "proportions": 0.8})
    fb64 = FitBody(AnnyBody(dtype=torch.float64))
    with torch.no_grad():
        ref, ref_sil, _ = fb64(sub.double(), trans.double(), phen.double())
        pts, sil = fit_body.points(sub, trans, fit_body.rest(phen))
    tol = 32 * torch.finfo(torch.float32).eps * float(ref.abs().max())
    torch.testing.assert_close(pts.double(), ref, atol=tol, rtol=0)
    torch.testing.assert_close(sil.double(), ref_sil, atol=tol, rtol=0)


def test_fast_points_are_differentiable_in_shape(fit_body):
    from relightnet.fit.body_model import phenotype_from_free

    base = fit_body.body.phenotype_tensor(None)[0]
    free = torch.zeros(3, requires_grad=True)
    rest = fit_body.rest(phenotype_from_free(free, base))
    pts, _ = fit_body.points(torch.zeros(1, len(FIT_BONES), 3), torch.zeros(1, 3), rest)
    height = pts[0, 0, 1] - pts[0, 29, 1]  # nose above heel
    height.backward()
    assert float(free.grad[0]) > 0  # "height" makes the body taller


def test_linearised_rest_is_first_order(fit_body):
    """rest_near's error vanishes to second order: halving the step quarters it (about), and it is
    a small part of the change it models."""
    from relightnet.fit.body_model import phenotype_from_free, rest_near

    base = fit_body.body.phenotype_tensor(None)[0]
    free0 = torch.tensor([0.2, -0.3, 0.1])
    rest0, jac = fit_body.rest_linearised(free0, base, step=1e-3)
    direction = torch.tensor([1.0, -0.5, 0.8])
    errs, changes = [], []
    for h in (0.4, 0.2):
        with torch.no_grad():
            exact = fit_body.rest(phenotype_from_free(free0 + h * direction, base))["blend"]
        near = rest_near(rest0, jac, h * direction)["blend"]
        errs.append(float((near - exact).abs().max()))
        changes.append(float((exact - rest0["blend"]).abs().max()))
    assert errs[0] < 0.1 * changes[0] and errs[1] < 0.1 * changes[1], (errs, changes)
    assert errs[1] < 0.5 * errs[0], errs  # second order: ~1/4, at most 1/2 with the differences' own error
