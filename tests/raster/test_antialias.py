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


def _random_scene(B=2, H=48, W=64, seed=0):
    from relightnet.raster import perspective_camera

    g = torch.Generator().manual_seed(seed)
    verts = torch.randn(120, 3, generator=g) * 0.6
    faces = torch.randint(0, 120, (160, 3), generator=g)
    cam = perspective_camera(look_at([0.0, 0.0, 4.0], [0.0, 0.0, 0.0]), (H, W), fov_deg=40)
    vc = cam.transform(verts).expand(B, -1, -1).contiguous()
    vc[-1, :, 0] += 0.1  # the second image differs
    return vc, faces, rasterize(vc, faces, (H, W))


def test_antialias_at_some_pixels_is_antialias_there():
    """antialias_pixels gives exactly antialias's values at the pixels asked for, from their colours only."""
    from relightnet.raster.antialias import antialias_pixels, silhouette_pixels

    vc, faces, frags = _random_scene()
    color = torch.rand(*frags.shape, 3)
    whole = antialias(color, frags, vc, faces).reshape(-1, 3)
    keep = torch.stack([silhouette_pixels(m) for m in frags.mask])
    asked = []

    def color_at(idx):
        asked.append(idx.numel())
        return color.reshape(-1, 3)[idx]

    idx, got = antialias_pixels(color_at, frags, vc, faces, keep)
    assert idx.numel() > 0 and keep.reshape(-1)[idx].all()
    assert torch.equal(got, whole[idx])
    changed = torch.nonzero((whole != color.reshape(-1, 3)).any(1) & keep.reshape(-1)).squeeze(1)
    assert set(changed.tolist()) <= set(idx.tolist())
    assert max(asked) < color.shape[0] * color.shape[1] * color.shape[2] // 2  # never a whole image of colours
    none = antialias_pixels(color_at, frags, vc, faces, torch.zeros_like(keep))
    assert none[0].numel() == 0 and none[1].shape == (0, 3)


def test_silhouette_pixels_are_those_with_a_neighbour_across():
    from relightnet.raster.antialias import silhouette_pixels

    g = torch.Generator().manual_seed(1)
    for shape in [(1, 1), (1, 6), (6, 1), (9, 11)]:
        m = torch.rand(shape, generator=g) < 0.5
        expect = torch.zeros(shape, dtype=torch.bool)
        for y in range(shape[0]):
            for x in range(shape[1]):
                for dy, dx in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                    yy, xx = y + dy, x + dx
                    if 0 <= yy < shape[0] and 0 <= xx < shape[1] and m[yy, xx] != m[y, x]:
                        expect[y, x] = True
        assert torch.equal(silhouette_pixels(m), expect) and torch.equal(silhouette_pixels(m.float()), expect)
