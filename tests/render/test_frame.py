import math

import pytest
import torch
import trimesh

from relightnet.checks import InputError, ShapeError
from relightnet.raster import default_camera, look_at, perspective_camera
from relightnet.render.frame import TexturedAlbedo, light_in_world, render_mesh
from relightnet.sh import irradiance, sh_basis, world_to_light
from relightnet.sh.irradiance import cosine_lobe_per_coeff


def _sphere(subdiv=3):
    m = trimesh.creation.icosphere(subdivisions=subdiv, radius=0.5)
    v = torch.tensor(m.vertices, dtype=torch.float32) + torch.tensor([0.0, 0.85, 0.0])
    f = torch.tensor(m.faces, dtype=torch.int64)
    n = torch.tensor(m.vertex_normals, dtype=torch.float32)
    return v, f, n


def _closed_form(n):
    return sh_basis(world_to_light(n), 2, check=False) * cosine_lobe_per_coeff(2)


def _light(seed=0):
    g = torch.Generator().manual_seed(seed)
    L = torch.randn(9, 3, generator=g) * 0.3
    L[0] += 2.0
    return L


def test_image_is_albedo_times_transport_dot_light_and_matches_irradiance():
    v, f, n = _sphere()
    T = _closed_form(n)
    L = _light()
    alb = torch.full((len(v), 3), 0.5)
    r = render_mesh(v, f, T, alb, L, default_camera(96), normals=n, maps=True)
    m = r.alpha[0] > 0
    assert 0.1 < m.float().mean() < 0.5
    # Exact consistency of the maps the data generator reuses.
    torch.testing.assert_close(r.image[0][m], (r.albedo[0] * (r.transport[0] @ L))[m], atol=1e-4, rtol=1e-4)
    torch.testing.assert_close(r.shading[0][m], (r.transport[0] @ L)[m], atol=1e-4, rtol=1e-4)
    # Closed form: shading = irradiance at the pixel normal (up to linear interpolation across faces).
    E = irradiance(L, world_to_light(r.normals[0][m]))
    assert ((r.shading[0][m] - E).abs().mean() / E.mean()) < 0.01
    assert torch.isinf(r.depth[0][~m]).all() and (r.depth[0][m] > 2).all()
    assert (r.image[0][~m] == 0).all()


def test_texture_albedo_equals_vertex_albedo_when_constant():
    v, f, n = _sphere(2)
    T = _closed_form(n)
    uv = torch.rand(len(v), 2)
    tex = TexturedAlbedo(torch.full((8, 8, 3), 0.3), uv, f)
    a = render_mesh(v, f, T, tex, _light(), default_camera(64))
    b = render_mesh(v, f, T, torch.full((len(v), 3), 0.3), _light(), default_camera(64))
    torch.testing.assert_close(a.image, b.image, atol=1e-5, rtol=1e-5)


def test_camera_relative_light_follows_the_camera():
    # A sphere lit by a camera-relative light looks the same from any viewpoint.
    v, f, n = _sphere(4)
    T = _closed_form(n)
    L = _light(1)
    alb = torch.full((len(v), 3), 0.5)
    target = torch.tensor([0.0, 0.85, 0.0])
    ra = render_mesh(v, f, T, alb, L, default_camera(64))
    a = ra.image
    for ang in (math.pi / 2, 2.0):
        eye = target + 3 * torch.nn.functional.normalize(torch.tensor([math.sin(ang), 0.3, math.cos(ang)]), dim=0)
        cam = perspective_camera(look_at(eye, target), 64, fov_deg=35)
        rb = render_mesh(v, f, T, alb, L, cam)
        both = (ra.alpha * rb.alpha)[..., None] > 0
        assert ((a - rb.image).abs() * both).sum() / both.sum() < 0.02 * a[both.expand_as(a)].mean()
    # ... whereas a world-fixed light does not follow it.
    rw = render_mesh(v, f, T, alb, L, cam, light_frame="world")
    both = (ra.alpha * rw.alpha)[..., None] > 0
    assert ((a - rw.image).abs() * both).sum() / both.sum() > 0.05 * a[both.expand_as(a)].mean()
    # The default camera's rotation is the identity: the light is unchanged.
    torch.testing.assert_close(light_in_world(L, default_camera(8))[0], L)


def test_batched_cameras_and_lights():
    v, f, n = _sphere(2)
    T = _closed_form(n)
    L = torch.stack([_light(0), _light(2)])
    cam = default_camera(48, batch_size=2)
    r = render_mesh(v, f, T, torch.full((len(v), 3), 0.5), L, cam)
    one = render_mesh(v, f, T, torch.full((len(v), 3), 0.5), L[1], default_camera(48))
    torch.testing.assert_close(r.image[1], one.image[0])


def test_bad_inputs():
    v, f, n = _sphere(1)
    T = _closed_form(n)
    with pytest.raises(ShapeError, match="transport"):
        render_mesh(v, f, T[:, :4], torch.ones(len(v), 3), _light(), default_camera(16))
    with pytest.raises(ShapeError, match="albedo"):
        render_mesh(v, f, T, torch.ones(3, 3), _light(), default_camera(16))
    with pytest.raises(InputError, match="light_frame"):
        render_mesh(v, f, T, torch.ones(len(v), 3), _light(), default_camera(16), light_frame="view")


def test_a_window_renders_the_frame_there():
    """render_mesh(window=): every image is the window's, the frame's render at its pixels (exactly: the
    window's fragments are the frame's bit for bit, and the shading of a pixel reads only its own); the
    covered pixels' radiance is kept compact, the dense image and alpha built on first use."""
    from relightnet.raster import Window, rasterize, screen_box

    v, f, n = _sphere(2)
    v = v + torch.tensor([0.55, 0.3, 0.0])  # cut by the frame's right border
    T = _closed_form(n)
    tex = TexturedAlbedo(torch.rand(16, 16, 3, generator=torch.Generator().manual_seed(0)), torch.rand(len(v), 2), f)
    cam = default_camera((48, 40))
    full = render_mesh(v, f, T, tex, _light(), cam, normals=n, maps=True)
    win = screen_box(cam.transform(v), f, cam.size, pad=2)
    assert win.left + win.width == 40 and win.height * win.width < 48 * 40 / 2
    part = render_mesh(v, f, T, tex, _light(), cam, normals=n, maps=True, window=win)
    assert "image" not in vars(part) and "alpha" not in vars(part)  # not made until asked for
    r, c = win.slices()
    assert part.image.shape == (1, win.height, win.width, 3) and part.frags.window == win
    for name in ("image", "alpha", "albedo", "shading", "transport", "normals", "depth"):
        assert torch.equal(getattr(part, name), getattr(full, name)[:, r, c]), name
    assert part.alpha.sum() == full.alpha.sum() > 0
    at = part.frags.pix
    assert torch.equal(part.image.reshape(-1, 3)[at], part.pix_image)
    again = render_mesh(v, f, T, tex, _light(), cam, frags=rasterize(cam.transform(v), f, cam.size, window=win),
                        window=win)
    assert torch.equal(again.pix_image, part.pix_image)
    with pytest.raises(InputError, match="window"):
        render_mesh(v, f, T, tex, _light(), cam, frags=part.frags, window=Window.full(cam.size))
