import pytest
import torch

from relightnet.checks import InputError
from relightnet.raster import texture
from relightnet.raster.texture import texture_pixels

# 2×2 texture, channel 0; row 0 is the TOP of the image (v = 1), row 1 the bottom (v = 0)
TEX = torch.tensor([[[[1.0, 2.0], [3.0, 4.0]]]])


def _uv(points):
    return torch.tensor(points, dtype=torch.float32).view(1, 1, -1, 2)


def test_texel_centres_and_v_orientation():
    # texel centres: u = 0.25 / 0.75, v = 0.75 (top row) / 0.25 (bottom row)
    uv = _uv([[0.25, 0.75], [0.75, 0.75], [0.25, 0.25], [0.75, 0.25]])
    for f in ("bilinear", "nearest"):
        assert torch.allclose(texture(TEX, uv, filter=f)[0, 0, :, 0], torch.tensor([1.0, 2.0, 3.0, 4.0]))


def test_bilinear_weights():
    out = texture(TEX, _uv([[0.5, 0.5], [0.5, 0.75], [0.25, 0.5], [0.375, 0.625]]))[0, 0, :, 0]
    assert torch.allclose(out, torch.tensor([2.5, 1.5, 2.0, 0.75 * 0.75 * 1 + 0.25 * 0.75 * 2
                                             + 0.75 * 0.25 * 3 + 0.25 * 0.25 * 4]))


def test_clamp_and_repeat_at_the_border():
    uv = _uv([[0.0, 0.75], [1.0, 0.25], [-0.25, 0.75]])
    clamp = texture(TEX, uv, wrap="clamp")[0, 0, :, 0]
    assert torch.allclose(clamp, torch.tensor([1.0, 4.0, 1.0]))
    rep = texture(TEX, uv, wrap="repeat")[0, 0, :, 0]
    # at u = 0 the sample lies halfway between the last and first columns
    assert torch.allclose(rep, torch.tensor([1.5, 3.5, 2.0]))
    assert torch.allclose(texture(TEX, _uv([[1.25, 1.75]]), wrap="repeat"), texture(TEX, _uv([[0.25, 0.75]])))


def test_batch_mask_and_gradients():
    tex = torch.rand(2, 3, 4, 5, requires_grad=True)
    uv = torch.rand(2, 6, 7, 2, requires_grad=True)
    out = texture(tex, uv)
    assert out.shape == (2, 6, 7, 3)
    shared = texture(tex[:1], uv)
    assert torch.allclose(shared[0], out[0])
    out.sum().backward()
    assert tex.grad.abs().sum() > 0 and uv.grad.abs().sum() > 0
    mask = torch.rand(2, 6, 7) > 0.5
    masked = texture(tex, uv, mask=mask)
    assert torch.allclose(masked[mask], out[mask])
    assert (masked[~mask] == 0).all()
    t64 = torch.rand(1, 2, 3, 3, dtype=torch.float64, requires_grad=True)
    uv64 = (torch.rand(1, 2, 2, 2, dtype=torch.float64) * 0.8 + 0.1).requires_grad_()
    assert torch.autograd.gradcheck(lambda t, c: texture(t, c), (t64, uv64))


def test_errors():
    with pytest.raises(InputError):
        texture(TEX, _uv([[0.5, 0.5]]), filter="cubic")
    with pytest.raises(InputError):
        texture(TEX, _uv([[0.5, 0.5]]), wrap="mirror")
    with pytest.raises(InputError):
        texture(torch.rand(3, 1, 2, 2), torch.rand(2, 1, 1, 2))


def test_texture_pixels_is_texture_at_the_covered_pixels():
    tex = torch.rand(2, 3, 4, 5)
    uv = torch.rand(2, 6, 7, 2) * 1.4 - 0.2  # some outside [0, 1]: the wrap modes matter
    mask = torch.rand(2, 6, 7) > 0.5
    pix = torch.nonzero(mask.reshape(-1)).squeeze(1)
    batch = pix // (6 * 7)
    for filt in ("bilinear", "nearest"):
        for wrap in ("clamp", "repeat"):
            dense = texture(tex, uv, filter=filt, wrap=wrap, mask=mask)
            got = texture_pixels(tex, uv.reshape(-1, 2)[pix], batch, filter=filt, wrap=wrap)
            assert torch.equal(got, dense.reshape(-1, 3)[pix])
    shared = texture_pixels(tex[:1], uv.reshape(-1, 2)[pix])
    assert torch.equal(shared, texture(tex[:1], uv).reshape(-1, 3)[pix])
    with pytest.raises(InputError, match="batch"):
        texture_pixels(tex, uv.reshape(-1, 2)[pix])  # two textures: which one?
    with pytest.raises(InputError, match="batch"):
        texture_pixels(tex, uv.reshape(-1, 2)[pix], batch + 1)
    with pytest.raises(InputError):
        texture_pixels(tex, uv.reshape(-1, 2)[pix], batch, filter="cubic")
