import torch

from relightnet.raster import antialias, look_at, orthographic_camera, rasterize

H, W = 8, 32


def _quad(x0, x1):
    """Orthographic scene: a quad covering pixel columns x0..x1 (continuous), all rows."""
    cam = orthographic_camera(look_at([0.0, 0.0, 5.0], [0.0, 0.0, 0.0]), (H, W), height=2.0, near=0.1, far=10.0)
    uv = torch.tensor([(x0, -5.0), (x1, -5.0), (x1, 15.0), (x0, 15.0)])
    verts = torch.stack([(uv[:, 0] / W * 2 - 1) * (W / H), 1 - uv[:, 1] / H * 2, torch.zeros(4)], 1)
    faces = torch.tensor([[0, 1, 2], [0, 2, 3]])
    vc = cam.transform(verts)
    return vc, faces, rasterize(vc, faces, (H, W))


def test_edge_pixels_get_their_coverage():
    vc, faces, frags = _quad(10.3, 20.7)
    color = frags.mask[..., None].float()
    aa = antialias(color, frags, vc, faces)[0, :, :, 0]
    expect = torch.zeros(W)
    expect[11:20] = 1.0
    expect[10] = expect[20] = 0.7  # pixel [10, 11] is 70 % right of x = 10.3; [20, 21] 70 % left of 20.7
    assert torch.allclose(aa, expect.expand(H, W), atol=1e-5)


def test_gradients_and_no_op_inside():
    vc, faces, frags = _quad(-50.0, 80.0)  # covers the whole image: nothing to blend
    color = torch.rand(1, H, W, 3)
    assert torch.allclose(antialias(color, frags, vc, faces), color)
    vc, faces, frags = _quad(10.3, 20.7)
    vc = vc.clone().requires_grad_()
    color = (frags.mask[..., None].float() * torch.tensor([1.0, 0.5, 0.2])).requires_grad_()
    antialias(color, frags, vc, faces).sum().backward()
    assert color.grad.abs().sum() > 0
    # moving the edges changes edge coverage: silhouette gradients reach the vertices
    assert vc.grad[..., 0].abs().sum() > 0
