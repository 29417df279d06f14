import numpy as np
import pytest
import torch
import trimesh

from relightnet.body import default_albedo, make_motion
from relightnet.checks import InputError
from relightnet.light import ambient_light, directional_light
from relightnet.prt import PrtSettings
from relightnet.render.frame import TexturedAlbedo
from relightnet.render.jobs import fit_camera, load_mesh, render_body_frames, render_mesh_file


def sphere_over_plane(path, n=31):
    """A sphere floating above a tessellated ground plane (per-vertex PRT needs vertices in the shadow)."""
    s = trimesh.creation.icosphere(3, 0.3)
    g = np.linspace(-1, 1, n)
    X, Z = np.meshgrid(g, g)
    V = np.stack([X.ravel(), np.full(X.size, -0.32), Z.ravel()], 1)
    F = [[i * n + j, (i + 1) * n + j, i * n + j + 1] for i in range(n - 1) for j in range(n - 1)]
    F += [[i * n + j + 1, (i + 1) * n + j, (i + 1) * n + j + 1] for i in range(n - 1) for j in range(n - 1)]
    (s + trimesh.Trimesh(V, np.array(F), process=False)).export(path)
    return path


def test_load_mesh_and_vertex_colours(tmp_path):
    m = trimesh.creation.box()
    m.visual.vertex_colors = np.tile([255, 0, 0, 255], (len(m.vertices), 1))
    m.export(tmp_path / "box.ply")
    mesh = load_mesh(tmp_path / "box.ply")
    assert mesh.faces.shape == (12, 3) and mesh.verts.shape == (8, 3)
    torch.testing.assert_close(mesh.albedo[0], torch.tensor([1.0, 0.0, 0.0]))
    torch.testing.assert_close(mesh.normals.norm(dim=-1), torch.ones(8))
    with pytest.raises(InputError, match="not found"):
        load_mesh(tmp_path / "nope.obj")
    (tmp_path / "junk.ply").write_bytes(b"ply\nformat nonsense\n")
    with pytest.raises(InputError, match="junk.ply"):
        load_mesh(tmp_path / "junk.ply")


def test_fit_camera_frames_the_mesh():
    v = torch.randn(200, 3) * torch.tensor([3.0, 1.0, 0.5]) + 10
    uv = fit_camera(v, (64, 96)).project(v)[0]
    assert (uv[:, 0] > 0).all() and (uv[:, 0] < 96).all() and (uv[:, 1] > 0).all() and (uv[:, 1] < 64).all()


def test_shadow_under_the_sphere(tmp_path):
    path = sphere_over_plane(tmp_path / "sp.ply")
    up = directional_light([0.0, 0.0, 1.0], 1.0, sharpness=20.0) + ambient_light(0.05)
    occ = render_mesh_file(path, up, size=96, prt=PrtSettings(n_dirs=128))
    flat = render_mesh_file(path, up, size=96, prt=PrtSettings(n_dirs=128, occlusion=False))
    # Ground pixels: normals pointing up. Under the sphere (image centre column) occlusion darkens them.
    ground = (occ.normals[0][..., 1] > 0.99) & (occ.alpha[0] > 0)
    dark = (occ.image[0].mean(-1) < 0.5 * flat.image[0].mean(-1)) & ground
    assert dark.sum() > 20 and dark.sum() < 0.5 * ground.sum()
    # Ground far to the sides of the sphere sees almost the whole sky either way.
    cols = torch.arange(96)
    far = ground & ((cols - 48).abs() > 22)[None, :]
    assert far.sum() > 20
    assert (occ.image[0][far] - flat.image[0][far]).abs().mean() < 0.05 * flat.image[0][far].mean()
    bounced = render_mesh_file(path, up, size=96, prt=PrtSettings(n_dirs=128, bounces=1))
    assert bounced.image[0][ground].mean() > occ.image[0][ground].mean()


@pytest.mark.slow
def test_render_body_frames_streams_a_motion(anny_body):
    motion = make_motion("walk", 3, seed=1)
    alb = default_albedo(anny_body, texture_size=64)
    frames = list(render_body_frames(anny_body, motion, ambient_light(1.0) + directional_light([1.0, 0.0, 0.0]),
                                     TexturedAlbedo(alb.texture, anny_body.uv, anny_body.uv_faces), camera=64,
                                     prt=PrtSettings(n_dirs=16), maps=True, vertex_albedo=alb.vertex))
    assert [f.index for f in frames] == [0, 1, 2]
    for f in frames:
        assert f.render.image.shape == (1, 64, 64, 3) and f.transport.shape == (anny_body.num_verts, 9)
        assert 0.02 < f.render.alpha.mean() < 0.5
    assert not torch.equal(frames[0].render.image, frames[2].render.image)
    seq = torch.stack([ambient_light(1.0)] * 2)
    with pytest.raises(InputError, match="2 frames but the motion has 3"):
        list(render_body_frames(anny_body, motion, seq, alb.vertex, camera=32, prt=PrtSettings(n_dirs=8)))


@pytest.mark.slow
def test_visible_only_transport_gives_the_same_frames(anny_body):
    """Transport at the vertices the camera sees only: the same images, chunked posing too.

    Posing 2 frames at a time instead of 3 changes the blocking of the skinning's float32 matmuls on
    some CPUs (AVX2 kernels): vertices move by a few ulps, and normals — differences of ~1 cm edges on
    a ~1 m body — carry that ~100× (relative). The images and transports then agree to
    ~100 · 4 ulps = 400 · ε₃₂ of their size (measured 1e-5 relative under ATEN_CPU_CAPABILITY=avx2,
    bit-identical with AVX-512)."""
    motion = make_motion("arm_raise", 3, seed=2)
    light = ambient_light(0.5) + directional_light([0.3, 0.8, 0.5])
    alb = torch.full((anny_body.num_verts, 3), 0.6)
    full = list(render_body_frames(anny_body, motion, light, alb, camera=64, prt=PrtSettings(n_dirs=16)))
    fast = list(render_body_frames(anny_body, motion, light, alb, camera=64, prt=PrtSettings(n_dirs=16),
                                   visible_only=True, n_frames=3, chunk=2))
    assert len(fast) == 3
    ulps = 400 * torch.finfo(torch.float32).eps
    for a, b in zip(full, fast, strict=True):
        img_tol = ulps * float(a.render.image.abs().max())
        torch.testing.assert_close(b.render.image, a.render.image, rtol=0, atol=img_tol)
        seen = b.transport.abs().sum(1) > 0
        assert 0.02 < seen.float().mean() < 0.6  # only vertices of faces hit by a pixel (not the back)
        t_tol = ulps * float(a.transport.abs().max())
        torch.testing.assert_close(b.transport[seen], a.transport[seen], rtol=0, atol=t_tol)


@pytest.mark.slow
def test_box_renders_the_frame_there(anny_body):
    """box=True: each frame's render is its body's screen box, the same pixels as the whole frame's (the
    same fragments, so the same vertices seen and the same transport); a body partly off-screen gets a box
    cut by the border, one wholly off-screen the frame's top-left pixel, covering nothing."""
    from relightnet.raster import Window, default_camera

    motion = make_motion("walk", 2, seed=3)
    light = ambient_light(0.5) + directional_light([0.3, 0.8, 0.5])
    alb = torch.full((anny_body.num_verts, 3), 0.6)
    for target, where in (((0.0, 0.85, 0.0), "inside"), ((0.45, 0.5, 0.0), "cut"), ((9.0, 0.85, 0.0), "off")):
        cam = default_camera((48, 36), target=target)
        kw = dict(camera=cam, prt=PrtSettings(n_dirs=8, occlusion=False), visible_only=True)
        full = list(render_body_frames(anny_body, motion, light, alb, **kw))
        box = list(render_body_frames(anny_body, motion, light, alb, box=True, **kw))
        for a, b in zip(full, box, strict=True):
            win = b.render.frags.window
            r, c = win.slices()
            assert torch.equal(b.render.image, a.render.image[:, r, c]) and torch.equal(b.transport, a.transport)
            assert b.render.alpha.sum() == a.render.alpha.sum()
            if where == "inside":
                assert 0 < win.left and win.left + win.width < 36 and win.height * win.width < 48 * 36 * 0.6
            elif where == "cut":
                assert win.left == 0 and win.top == 0 and a.render.alpha.sum() > 0  # cut at the left and top
            else:
                assert win == Window(0, 0, 1, 1, (48, 36)) and a.render.alpha.sum() == 0


def test_interleaved_frame_streams_leave_grad_mode_as_it_was(anny_body):
    """Two streams advanced in turn (zip), one abandoned half-way: grad mode is what it was before, in
    the consumer between frames and afterwards (a generator suspended inside ``torch.no_grad()`` leaked
    its state: two interleaved streams left grad mode off for the rest of the process)."""
    motion = make_motion("walk", 2, seed=1)
    alb = default_albedo(anny_body, texture_size=16).vertex
    kw = dict(camera=16, prt=PrtSettings(n_dirs=4, occlusion=False), n_frames=2, chunk=1)
    assert torch.is_grad_enabled()
    for a, b in zip(render_body_frames(anny_body, motion, ambient_light(1.0), alb, **kw),
                    render_body_frames(anny_body, motion, ambient_light(1.0), alb, **kw), strict=True):
        assert torch.is_grad_enabled() and not a.render.image.requires_grad and torch.equal(a.transport, b.transport)
    stream = render_body_frames(anny_body, motion, ambient_light(1.0), alb, **kw)
    next(stream)
    assert torch.is_grad_enabled()
    del stream
    assert torch.is_grad_enabled()
