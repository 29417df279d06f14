import pytest
import torch

from relightnet.checks import ShapeError
from relightnet.raster import interpolate, look_at, perspective_camera, rasterize, to_channels_first, to_channels_last
from relightnet.raster.interpolate import Interpolate, interpolate_pixels

SIZE = (24, 32)


def _scene(dtype=torch.float32):
    """A tilted quad seen in perspective: 4 vertices, 2 triangles."""
    verts = torch.tensor([[-1.0, -0.8, 0.3], [1.2, -0.7, -0.6], [0.9, 0.9, -0.9], [-1.1, 0.8, 0.2]], dtype=dtype)
    faces = torch.tensor([[0, 1, 2], [0, 2, 3]])
    cam = perspective_camera(look_at([0.2, 0.1, 2.5], [0.0, 0.0, 0.0], dtype=dtype), SIZE, fov_deg=60.0)
    return verts, faces, cam


def test_interpolated_positions_project_to_pixel_centres():
    """Perspective-correct: interpolating world positions gives the surface point under each pixel."""
    verts, faces, cam = _scene(torch.float64)
    frags = rasterize(cam.transform(verts), faces, SIZE)
    pos = interpolate(verts, frags, faces)
    mask = frags.mask[0]
    assert mask.sum() > 150
    uv = cam.project(pos[0][mask])[0]
    rows, cols = torch.nonzero(mask, as_tuple=True)
    centres = torch.stack([cols + 0.5, rows + 0.5], dim=1).double()
    assert torch.allclose(uv, centres, atol=1e-6)
    # and the points lie on the quad's triangles: depth agrees with the rasterizer's
    c = cam.transform(pos[0][mask])[0]
    assert torch.allclose(c[:, 2] / c[:, 3], frags.depth[0][mask], atol=1e-9)
    assert (pos[0][~mask] == 0).all()


def test_constant_and_batched_attributes():
    verts, faces, cam = _scene()
    vc = cam.transform(verts).expand(2, -1, -1)
    frags = rasterize(vc, faces, SIZE)
    const = interpolate(torch.full((4, 2), 3.0), frags, faces)
    assert torch.allclose(const[frags.mask], torch.full((int(frags.mask.sum()), 2), 3.0))
    per_batch = torch.stack([torch.rand(4, 5), torch.rand(4, 5)])
    out = interpolate(per_batch, frags, faces)
    for b in range(2):
        assert torch.allclose(out[b], interpolate(per_batch[b], frags, faces)[b])
    assert out.shape == (2, *SIZE, 5)
    assert torch.allclose(Interpolate(faces)(per_batch, frags), out)
    compact = interpolate_pixels(per_batch, frags, faces)
    assert torch.allclose(out.reshape(-1, 5)[frags.pix], compact)


def test_gradcheck_float64():
    verts, faces, cam = _scene(torch.float64)
    frags = rasterize(cam.transform(verts), faces, (6, 8))
    assert frags.mask.sum() > 10
    attr = torch.rand(4, 3, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(lambda a: interpolate(a, frags, faces), (attr,))
    battr = torch.rand(1, 4, 2, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(lambda a: interpolate(a, frags, faces), (battr,))


def test_shape_errors():
    verts, faces, cam = _scene()
    frags = rasterize(cam.transform(verts), faces, SIZE)
    with pytest.raises(ShapeError):
        interpolate(torch.rand(3, 4, 2), frags, faces)
    with pytest.raises(ShapeError):
        interpolate(torch.rand(4), frags, faces)


def test_channels_round_trip():
    x = torch.rand(2, 5, 6, 3)
    cf = to_channels_first(x)
    assert cf.shape == (2, 3, 5, 6)
    assert torch.equal(cf[1, 2], x[1, :, :, 2])
    assert torch.equal(to_channels_last(cf), x)
    assert to_channels_first(x[0]).shape == (3, 5, 6)
    assert torch.equal(to_channels_last(to_channels_first(x[0])), x[0])
    with pytest.raises(ShapeError):
        to_channels_first(torch.rand(3, 4))


def test_out_buffer_is_reused():
    verts, faces, cam = _scene()
    frags = rasterize(cam.transform(verts), faces, SIZE)
    attr = torch.rand(4, 3)
    buf = torch.full((1, *SIZE, 3), 7.0)
    res = interpolate(attr, frags, faces, out=buf)
    assert res.data_ptr() == buf.data_ptr()
    assert torch.equal(res, interpolate(attr, frags, faces))
    with pytest.raises(ShapeError):
        interpolate(attr, frags, faces, out=torch.zeros(1, *SIZE, 2))
