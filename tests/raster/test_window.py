"""A window of the frame rasterized on its own is the frame's rasterization there, bit for bit.

Exact equality, no tolerance: the window changes no float operation. The triangles are snapped in the
frame's pixel coordinates (the same integers), the rows and columns are the frame's (only the range
enumerated and the flat index written change), and a pixel centre's NDC is computed from its frame
column and row with the same operations; so the z-buffer keys, the winners, the barycentrics and the
depths are the same bits (and antialiasing, which reads them and the pixel centres, too).
"""

import pytest
import torch

from relightnet.checks import InputError
from relightnet.raster import Window, antialias, look_at, orthographic_camera, perspective_camera, rasterize, screen_box
from relightnet.raster.antialias import antialias_pixels, silhouette_pixels

H, W = 40, 56


def _same(full, part, win):
    """``part`` (a window's fragments) holds exactly ``full``'s at the window's pixels."""
    r, c = win.slices()
    assert part.shape == (full.shape[0], win.height, win.width) and part.window == win
    for name in ("face_id", "bary", "depth", "mask"):
        assert torch.equal(getattr(full, name)[:, r, c], getattr(part, name)), name


def _check_box(vc, faces, size=(H, W), cull=False):
    """screen_box holds every covered pixel and its 4-neighbours; its render and antialiasing are the frame's."""
    full = rasterize(vc, faces, size, cull_backfaces=cull)
    win = screen_box(vc, faces, size, pad=1)
    assert win is not None
    part = rasterize(vc, faces, size, cull_backfaces=cull, window=win)
    _same(full, part, win)
    r, c = win.slices()
    assert part.mask.sum() == full.mask.sum() > 0  # nothing covered outside the window
    grown = full.mask.clone()
    grown[:, 1:] |= full.mask[:, :-1]
    grown[:, :-1] |= full.mask[:, 1:]
    grown[:, :, 1:] |= full.mask[:, :, :-1]
    grown[:, :, :-1] |= full.mask[:, :, 1:]
    assert grown[:, r, c].sum() == grown.sum()  # pad 1: the neighbours of covered pixels too
    color = torch.rand(*full.shape, 3, generator=torch.Generator().manual_seed(1))
    aa = antialias(color, full, vc, faces)
    assert torch.equal(antialias(color[:, r, c].contiguous(), part, vc, faces), aa[:, r, c])
    outside = torch.ones(full.shape, dtype=torch.bool)
    outside[:, r, c] = False
    assert torch.equal(aa[outside], color[outside])  # antialiasing changes nothing outside the window
    return full, win


def _camera(eye=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), size=(H, W), fov=50.0, dtype=torch.float32):
    view = look_at(torch.tensor(eye, dtype=dtype), torch.tensor(target, dtype=dtype), dtype=dtype)
    return perspective_camera(view, size, fov_deg=fov, near=0.1, far=20.0)


def _quad(x0, x1, y0, y1, z=0.0):
    verts = torch.tensor([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]])
    return verts, torch.tensor([[0, 1, 2], [0, 2, 3]])


def _blob(n=60, f=90, seed=0, centre=(0.0, 0.0, 0.0), spread=0.5):
    g = torch.Generator().manual_seed(seed)
    verts = torch.randn(n, 3, generator=g) * spread + torch.tensor(centre)
    return verts, torch.randint(0, n, (f, 3), generator=g)


def test_window_contract():
    win = Window(2, 3, 4, 5, (10, 12))
    assert win.size == (4, 5) and not win.is_full and Window.full((10, 12)).is_full
    img = torch.arange(2 * 10 * 12).view(2, 10, 12)
    r, c = win.slices()
    local = torch.arange(2 * 4 * 5)
    assert torch.equal(img.view(-1)[win.to_frame(local)], img[:, r, c].reshape(-1))
    for bad in ((0, 0, 0, 5), (-1, 0, 4, 5), (7, 0, 4, 5), (0, 8, 4, 5), (0, 0, 4, 13)):
        with pytest.raises(InputError, match="window"):
            Window(*bad, (10, 12))


@pytest.mark.parametrize("seed", range(3))
def test_any_window_is_the_frame_there(seed):
    """Random triangles around and behind the camera (clipped at the near plane and the guard band),
    two cameras in the batch, float64 and float32, with and without culling: every window is exact."""
    verts, faces = _blob(n=40, f=30, seed=seed, spread=1.5)
    view = look_at(torch.tensor([[0.0, 0, 2.0], [0.3, 0.2, 1.5]]), torch.tensor([0.0, 0, 0]))
    vc = perspective_camera(view, (H, W), fov_deg=60.0).transform(verts)
    assert (vc[..., 3] <= 0).any()  # vertices behind the camera
    g = torch.Generator().manual_seed(seed)
    for dtype, cull in ((torch.float32, False), (torch.float64, True)):
        full = rasterize(vc.to(dtype), faces, (H, W), cull_backfaces=cull)
        for _ in range(4):
            top, left = (int(torch.randint(0, n - 1, (1,), generator=g)) for n in (H, W))
            h, w = int(torch.randint(1, H - top + 1, (1,), generator=g)), int(torch.randint(1, W - left + 1, (1,),
                                                                                          generator=g))
            win = Window(top, left, h, w, (H, W))
            _same(full, rasterize(vc.to(dtype), faces, (H, W), cull_backfaces=cull, window=win), win)
        _same(full, rasterize(vc.to(dtype), faces, (H, W), cull_backfaces=cull, window=Window.full((H, W))),
              Window.full((H, W)))


def test_box_of_a_mesh_inside_and_partly_off_screen():
    verts, faces = _blob(centre=(0.3, -0.1, 0.0), spread=0.25)
    full, win = _check_box(_camera().transform(verts), faces)
    assert win.height * win.width < H * W / 2  # a box, not the frame
    verts, faces = _blob(n=80, f=120, centre=(1.2, 0.0, 0.0), spread=0.6)  # cut by the right border
    _, win = _check_box(_camera().transform(verts), faces, cull=True)
    assert win.left + win.width == W


def test_box_of_a_mesh_crossing_the_near_plane():
    """A floor running from far in front of the camera to behind it: only its clipped part counts."""
    verts, faces = _quad(-3.0, 3.0, -10.0, 10.0)
    verts = verts[:, [0, 2, 1]] * torch.tensor([1.0, 1.0, -1.0]) + torch.tensor([0.0, -0.6, 0.0])  # y = −0.6
    vc = _camera(eye=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0)).transform(verts)
    assert (vc[..., 3] < 0).any() and (vc[..., 3] > 0).any()
    _, win = _check_box(vc, faces)
    assert win.top > 0 and win.top + win.height == H  # the floor below the horizon, nothing above it


@pytest.mark.parametrize("side", ["left", "right", "top", "bottom"])
def test_box_touching_each_border(side):
    """A quad half outside one side of an orthographic frame: the box reaches that border (and only that one)."""
    cam = orthographic_camera(look_at([0.0, 0.0, 5.0], [0.0, 0.0, 0.0]), (H, W), height=2.0, near=0.1, far=10.0)
    half_w = W / H  # NDC x = 1 at world x = W / H
    x0, x1, y0, y1 = {"left": (-half_w - 0.3, -half_w + 0.4, -0.3, 0.2),
                      "right": (half_w - 0.4, half_w + 0.3, -0.2, 0.3),
                      "top": (-0.3, 0.2, 0.6, 1.3), "bottom": (-0.2, 0.3, -1.3, -0.6)}[side]
    verts, faces = _quad(x0, x1, y0, y1)
    _, win = _check_box(cam.transform(verts), faces)
    touches = {"left": win.left == 0, "right": win.left + win.width == W, "top": win.top == 0,
               "bottom": win.top + win.height == H}
    assert [k for k, v in touches.items() if v] == [side]


def test_box_is_tight_and_padded():
    """A quad whose corners lie between pixel centres: the box is its covered pixels grown by ``pad``, cut to
    the frame."""
    cam = orthographic_camera(look_at([0.0, 0.0, 5.0], [0.0, 0.0, 0.0]), (H, W), height=2.0, near=0.1, far=10.0)

    def world(u, v):  # continuous pixel coordinates → world x, y (z = 0)
        return (u / W * 2 - 1) * (W / H), 1 - v / H * 2

    (x0, y0), (x1, y1) = world(10.2, 30.7), world(20.6, 5.3)  # covers columns 10..20, rows 5..30
    verts, faces = _quad(x0, x1, y0, y1)
    vc = cam.transform(verts)
    assert screen_box(vc, faces, (H, W), pad=0) == Window(5, 10, 26, 11, (H, W))
    assert screen_box(vc, faces, (H, W), pad=3) == Window(2, 7, 32, 17, (H, W))
    assert screen_box(vc, faces, (H, W), pad=100) == Window.full((H, W))
    with pytest.raises(InputError, match="pad"):
        screen_box(vc, faces, (H, W), pad=-1)
    with pytest.raises(InputError, match="window"):
        rasterize(vc, faces, (H, W), window=Window(0, 0, 4, 4, (H + 1, W)))


def test_nothing_on_screen_has_no_box():
    """Beside the frame, behind the camera, or between pixel centres: no box, and no window covers anything."""
    verts, faces = _blob(spread=0.2)
    cam = _camera()
    for shift in ((6.0, 0.0, 0.0), (0.0, -5.0, 0.0), (0.0, 0.0, 8.0)):  # right, below, behind the camera
        vc = cam.transform(verts + torch.tensor(shift))
        assert screen_box(vc, faces, (H, W)) is None
        assert rasterize(vc, faces, (H, W)).pix.numel() == 0
        assert rasterize(vc, faces, (H, W), window=Window(0, 0, 1, 1, (H, W))).pix.numel() == 0
    tiny = cam.transform(torch.tensor([[0.001, 0.001, 0.0], [0.002, 0.001, 0.0], [0.001, 0.002, 0.0]]))
    assert screen_box(tiny, torch.tensor([[0, 1, 2]]), (H, W)) is None  # no pixel centre in its box
    assert screen_box(cam.transform(verts), faces[:0], (H, W)) is None


def test_silhouette_of_a_window_is_antialiased_as_in_the_frame():
    """antialias_pixels at the silhouette of a box's render: the frame's values, the window's pixel indices."""
    verts, faces = _blob(centre=(-0.4, 0.2, 0.0), spread=0.3)
    vc = _camera().transform(verts)
    full = rasterize(vc, faces, (H, W))
    win = screen_box(vc, faces, (H, W), pad=1)
    part = rasterize(vc, faces, (H, W), window=win)
    color = torch.rand(1, H, W, 3, generator=torch.Generator().manual_seed(2))
    flat = color.reshape(-1, 3)
    idx_f, col_f = antialias_pixels(lambda i: flat[i], full, vc, faces, silhouette_pixels(full.mask[0])[None])
    idx_w, col_w = antialias_pixels(lambda i: flat[win.to_frame(i)], part, vc, faces,
                                    silhouette_pixels(part.mask[0])[None])
    assert idx_f.numel() > 10
    order = torch.argsort(win.to_frame(idx_w))
    assert torch.equal(win.to_frame(idx_w)[order], idx_f) and torch.equal(col_w[order], col_f)
