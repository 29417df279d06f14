"""What the avatar's outfits add to the generator's clothes: shoes that follow the feet, hems cut smooth."""

import numpy as np
import pytest
import torch

from relightnet.body import make_motion
from relightnet.names import OUTFITS
from relightnet.pipeline.outfit_parts import SHOE_UV_HEIGHT, shoe_panel
from relightnet.pipeline.outfits import OUTFIT_SHOES, DressedBody, draw_outfit
from relightnet.pipeline.smooth_albedo import boundary_jaggedness
from relightnet.raster import look_at, perspective_camera, rasterize

#: Close-ups (eye, target) of the hems: neckline, trouser hem, waist, sleeve end, face opening.
HEM_VIEWS = (((0.0, 1.3, 1.0), (0.0, 1.25, 0.0)), ((0.1, 0.25, 0.6), (0.1, 0.15, 0.0)),
             ((0.0, 0.95, 1.0), (0.0, 0.95, 0.0)), ((0.6, 1.1, 0.6), (0.25, 1.1, 0.0)),
             ((0.0, 1.62, 0.55), (0.0, 1.6, 0.0)))
RES = 512


def _camera(eye, target):
    return perspective_camera(look_at(torch.tensor(eye), torch.tensor(target)), (RES, RES), fov_deg=35)


def _face_ids(verts: torch.Tensor, faces: torch.Tensor, eye, target) -> np.ndarray:
    cam = _camera(eye, target)
    return rasterize(cam.transform(verts), faces, (RES, RES)).face_id[0].numpy()


def _distance(verts: torch.Tensor, faces: torch.Tensor, cam) -> tuple[np.ndarray, np.ndarray]:
    """(face ids, view distance in metres, +inf on background) of a render, (H, W) each."""
    fr = rasterize(cam.transform(verts), faces, (RES, RES))
    return fr.face_id[0].numpy(), cam.depth_to_view(fr.depth)[0].numpy()


def _covered_foot(dressed: DressedBody) -> torch.Tensor:
    """(V,) bool body vertices of the feet 1.5 cm or more under the shoes' collars (at rest)."""
    from relightnet.body.shoes import SHOE_KINDS

    body = dressed.body
    names = list(body.joint_names)
    w, bi = body.anny.vertex_bone_weights, body.anny.vertex_bone_indices.long()
    dom = np.array(names)[bi.gather(1, w.argmax(1, keepdim=True))[:, 0].numpy()]
    foot = torch.as_tensor(np.char.startswith(dom, "foot") | np.char.startswith(dom, "toe"))
    with torch.no_grad():
        rest = body()
    ankle = float(rest.joints[0, names.index("foot.L"), 1])
    return foot & (rest.verts[0, :, 1] < ankle + SHOE_KINDS[dressed.shoes.kind]["collar"] - 0.015)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["casual", "coat"])
def test_shoes_hide_the_feet_through_a_walk(anny_body, name):
    """No pixel of a foot under a shoe shows in side and front close-ups of the feet through a walk, and the
    shoes move with the feet (a rigid follow: the covered foot points stay within the shoe's clearance band)."""
    d = DressedBody(anny_body, draw_outfit(name))
    assert d.shoes.kind == OUTFIT_SHOES[name] and d.types[-1] == "shoes"
    out = d(make_motion("walk", 6))
    covered = _covered_foot(d)
    F_body = anny_body.faces.shape[0]
    hidden = covered[anny_body.faces].all(1)
    seen, body_px = 0, 0
    for t in range(0, 6, 2):
        for eye, target in (((0.7, 0.25, 0.5), (0.0, 0.08, 0.05)), ((0.0, 0.3, 0.9), (0.0, 0.08, 0.0)),
                            ((-0.7, 0.25, 0.5), (0.0, 0.08, 0.05))):
            fid = _face_ids(out.verts[t], out.faces, eye, target)
            body = fid[(fid >= 0) & (fid < F_body)]
            seen += int(hidden[torch.as_tensor(body)].sum())
            body_px += len(body)
        # The shoes moved with the feet: every covered foot vertex lies within 6 cm of the shoe's surface.
        shoe = out.verts[t, -len(d.shoes.rest):]
        dist = torch.cdist(out.verts[t, :anny_body.num_verts][covered], shoe).amin(1)
        assert float(dist.max()) < 0.06
    assert body_px > 1000 and seen == 0, (seen, body_px)


def test_shoe_panel_paints_sole_welt_and_upper():
    up = (0.3, 0.2, 0.1)
    p = shoe_panel(300, "sneaker", up).numpy()
    h = (1 - (np.arange(300) + 0.5) / 300) * SHOE_UV_HEIGHT
    assert np.allclose(p[h < 0.02, 0], [0.72, 0.71, 0.68]) and np.allclose(p[h > 0.03, 7], up)
    assert np.allclose(p[(h > 0.0225) & (h < 0.0245), 0], np.asarray(up) * 0.55)


def _hem_labels(d: DressedBody, verts: torch.Tensor, eye, target) -> np.ndarray:
    """(H, W) 1 where a pixel shows a piece whose hems are cut (shells, hoods, long hair), 0 the body, −1 else.

    Body pixels with such a piece less than 2 cm behind them are −1 too: there the line between body and
    cloth is where the body crosses the cloth (hair resting on a shoulder), not a hem."""
    kinds = ("loose_top", "jacket", "open_coat", "trousers", "wide_trousers", "volume_hair", "hood", "long_hair")
    cut = torch.as_tensor([k for k, t in enumerate(d.types) if t in kinds])
    cam = _camera(eye, target)
    fid, dist = _distance(verts, d.faces, cam)
    _, behind = _distance(verts, d.faces[torch.isin(d.face_piece, cut)], cam)
    piece = d.face_piece.numpy()[np.maximum(fid, 0)]
    lab = np.where(np.isin(piece, cut.numpy()), 1, np.where(piece == -1, 0, -1))
    lab[(lab == 0) & np.isfinite(behind) & (behind < dist + 0.02)] = -1
    return np.where(fid >= 0, lab, -1)


@pytest.mark.slow
@pytest.mark.parametrize("name", OUTFITS)
def test_no_stair_stepped_hem_in_any_outfit(anny_body, name):
    """Target: the hems of every named outfit, rendered at 512² in close-ups, stray from their own
    10-pixel smoothing by less than 0.85 px (the smooth reference's bound, as for the default albedo, whose
    face-wise zig-zag strays by about 1.4 px; a smooth curve by a fraction of a pixel), and on the whole by
    less than the generator's face-wise borders do."""
    new, old = DressedBody(anny_body, draw_outfit(name)), DressedBody(anny_body, draw_outfit(name), hems=False)
    j_new, j_old = [], []
    for d, js in ((new, j_new), (old, j_old)):
        out = d()
        for eye, target in HEM_VIEWS:
            js.append(boundary_jaggedness(_hem_labels(d, out.verts[0], eye, target), 1, 0, sigma=10))
    j_new, j_old = np.asarray(j_new), np.asarray(j_old)
    have = ~np.isnan(j_new)
    assert have.sum() >= 2 and float(np.nanmax(j_new)) < 0.85, (name, j_new, j_old)
    assert float(j_new[have].mean()) < float(np.nanmean(j_old[have])), (name, j_new, j_old)


def test_every_outfit_wears_shoes_and_random_ones_draw_their_kind():
    from relightnet.body.shoes import SHOE_KINDS

    assert {draw_outfit(n).shoes for n in OUTFITS} <= set(SHOE_KINDS) and set(OUTFIT_SHOES) == set(OUTFITS)
    kinds = [draw_outfit(f"random:{s}").shoes for s in range(12)]
    assert set(kinds) == set(SHOE_KINDS) and kinds == [draw_outfit(f"random:{s}").shoes for s in range(12)]
