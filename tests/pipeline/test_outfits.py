"""The dressed avatar: outfit draws, the garments skinned to the body, one PRT over body and cloth, --outfit."""

import numpy as np
import pytest
import torch

from relightnet.body import make_motion
from relightnet.checks import InputError
from relightnet.cli import main
from relightnet.data.garments import garment_types
from relightnet.io import read_image
from relightnet.names import OUTFITS
from relightnet.pipeline.outfits import OUTFIT_SLOTS, DressedBody, draw_outfit
from relightnet.prt import PrtSettings, vertex_transport


@pytest.fixture(scope="module")
def coat(anny_body):
    return DressedBody(anny_body, draw_outfit("coat"))


def test_named_outfits_wear_their_slots_and_draws_are_seeded():
    assert set(OUTFITS) == set(OUTFIT_SLOTS)
    for name in OUTFITS:
        d = draw_outfit(name)
        slots, _ = OUTFIT_SLOTS[name]
        assert (d.garments["upper"], d.garments["lower"], d.garments["head"], d.garments["hair"]) == slots
        assert d.look["hair"] is not None and d == draw_outfit(name)
    a, b = draw_outfit("random:1"), draw_outfit("random:1")
    assert a.look == b.look and a.garments == b.garments
    looks = {str(draw_outfit(f"random:{s}").look["top"]["color"]) for s in range(4)}
    assert len(looks) == 4
    for bad in ("nope", "random:x", "random:-1", ""):
        with pytest.raises(InputError, match="--outfit"):
            draw_outfit(bad)


def test_dressed_mesh_is_the_body_then_its_garments_every_frame(coat, anny_body):
    motion = make_motion("walk", 3)
    out = coat(motion)
    body = anny_body(motion)
    V = anny_body.num_verts
    assert torch.equal(out.verts[:, :V], body.verts.float()) and out.verts.shape[1] == coat.num_verts
    assert torch.equal(out.faces[: anny_body.faces.shape[0]], anny_body.faces)
    assert coat.types == [*garment_types(coat.outfit.garments), "shoes"] == ["open_coat", "trousers", "hat",
                                                                             "volume_hair", "shoes"]
    assert coat.albedo.uv_faces.shape == out.faces.shape and int(coat.albedo.uv_faces.max()) < len(coat.albedo.uv)
    # Skinned: garment vertices move with the body (the coat's sleeves swing with the arms).
    move_body = (body.verts[2] - body.verts[0]).norm(dim=1).max()
    move_cloth = (out.verts[2, V:] - out.verts[0, V:]).norm(dim=1)
    assert float(move_cloth.max()) > 0.5 * float(move_body)
    # ... and stay near it: every garment vertex lies within 25 cm of some body vertex.
    d = torch.cdist(out.verts[1, V:], body.verts[1].float()).amin(1)
    assert float(d.max()) < 0.25


@pytest.mark.slow
def test_dressed_body_at_rest_is_the_generators_clothed_mesh(coat, anny_body):
    from relightnet.data.clothed import clothed_mesh
    from relightnet.data.sample import prepare_assets
    from relightnet.data.textures import paint_albedo, uv_atlas
    from relightnet.pipeline.outfits import outfit_field

    a = prepare_assets(anny_body)
    look, g = coat.outfit.look, coat.outfit.garments
    field = outfit_field(anny_body, look, a)  # painted as the avatar paints: its field, a 1024² atlas
    atlas = uv_atlas(anny_body, 1024)
    r = anny_body()
    m = clothed_mesh(g, look, r.verts, r.normals, r.joints, anny_body, a.garment_tables(),
                     paint_albedo(atlas, field, look), field, atlas, subdivide=False)
    out = coat()
    n = m.verts.shape[1]  # the clothed mesh's vertices come first, then the hems' new ones, then the shoes'
    assert torch.allclose(out.verts[0, :n], m.verts[0], atol=1e-6)
    assert torch.allclose(out.normals[0, :n], m.normals[0], atol=1e-5)
    assert out.verts.shape[1] == n + len(coat.cut.edges) + len(coat.shoes.rest)
    # Every face the hems do not cut is the clothed mesh's, in its order; the body's are all kept.
    whole = coat.cut.faces[: int((coat.cut.faces < n).all(1).sum())]
    assert torch.equal(out.faces[: m.n_body_faces], m.faces[: m.n_body_faces])
    assert len(whole) < len(m.faces) and bool(torch.isin(whole.flatten(), m.faces.flatten()).all())
    # The texture: the clothed mesh's panels, then the shoe panel.
    S = m.tex.shape[0]
    assert torch.equal(coat.albedo.tex[:, : m.tex.shape[1]], m.tex) and coat.albedo.tex.shape[1] == m.tex.shape[1] + S
    # subdivide=True: the generator's own ground-truth mesh (its cloth's outer sides split once)
    fine = clothed_mesh(g, look, r.verts, r.normals, r.joints, anny_body, a.garment_tables(),
                        paint_albedo(atlas, field, look), field, atlas)
    out = DressedBody(anny_body, coat.outfit, subdivide=True)()
    nf = fine.verts.shape[1]
    assert len(fine.midpoints) > 0 and nf > n and torch.allclose(out.verts[0, :nf], fine.verts[0], atol=1e-6)


def test_cloth_shadows_the_body_in_the_one_prt(coat, anny_body):
    out = coat()
    V = anny_body.num_verts
    naked = anny_body()
    torso = torch.nonzero((naked.verts[0, :, 1] > 1.0) & (naked.verts[0, :, 1] < 1.3)).flatten()
    kw = dict(lmax=1, prt=PrtSettings(n_dirs=64, seed=0, occlusion=True), vertices=torso, manifold="ignore")
    dressed = vertex_transport(out.verts[0], out.faces, out.normals[0], **kw)[torso, 0]
    bare = vertex_transport(naked.verts[0], naked.faces, naked.normals[0], **kw)[torso, 0]
    assert float(dressed.mean()) < 0.5 * float(bare.mean())
    assert out.verts.shape[1] > V


@pytest.mark.slow
def test_render_body_outfit_cli(tmp_path, capsys):
    out = tmp_path / "d.png"
    base = ["-q", "render-body", "--light", "studio", "--res", "96", "--n-dirs", "8", "--out", str(out)]
    assert main([*base, "--outfit", "dress"]) == 0
    img = read_image(out).numpy()
    assert img.shape == (96, 96, 3) and img.max() > 0.2
    out.unlink()
    assert main([*base, "--outfit", "random:x"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--outfit random:x" in err[0] and not out.exists()


def test_avatar_outfit_refuses_an_albedo(tmp_path, capsys):
    from relightnet.io import VideoWriter

    video = tmp_path / "t.mkv"
    with VideoWriter(video, fps=10) as w:
        for _ in range(2):
            w.write(np.zeros((32, 32, 3), np.uint8))
    tex = tmp_path / "tex.png"
    from relightnet.io import write_image

    write_image(tex, np.full((8, 8, 3), 128, np.uint8), srgb=False)
    argv = ["-q", "avatar", "--target", str(video), "--light", "studio", "--outfit", "casual", "--albedo", str(tex),
            "--out", str(tmp_path / "a.mkv")]
    assert main(argv) == 1
    assert "--albedo" in capsys.readouterr().err and not (tmp_path / "a.mkv").exists()
