"""Shoes as geometry: a closed, outward shell around the real Anny foot, with a flat sole."""

import numpy as np
import pytest
import torch

from relightnet.body.shoes import SHOE_KINDS, shoe_surface
from relightnet.checks import InputError


def _foot(anny_body, side="L"):
    """The rest foot's points (the vertices the foot, toe and lower-leg bones dominate), ankle and toe joints."""
    with torch.no_grad():
        out = anny_body()
    names = list(anny_body.joint_names)
    w, bi = anny_body.anny.vertex_bone_weights, anny_body.anny.vertex_bone_indices.long()
    dom = np.array(names)[bi.gather(1, w.argmax(1, keepdim=True))[:, 0].numpy()]
    sel = np.flatnonzero((np.char.startswith(dom, "foot") | np.char.startswith(dom, "toe")
                          | np.char.startswith(dom, "lowerleg")) & np.char.endswith(dom, f".{side}"))
    j = out.joints[0]
    toe = j[[names.index(f"toe{k}-1.{side}") for k in range(1, 6)]].mean(0)
    return out.verts[0][sel], j[names.index(f"foot.{side}")], toe


def _winding(points: torch.Tensor, verts: torch.Tensor, faces: torch.Tensor) -> torch.Tensor:
    """(N,) generalised winding number of a closed mesh at the points (1 inside, 0 outside; Jacobson et al.)."""
    a, b, c = (verts[faces[:, k]].double()[None] - points.double()[:, None] for k in range(3))
    la, lb, lc = a.norm(dim=-1), b.norm(dim=-1), c.norm(dim=-1)
    det = (a * torch.linalg.cross(b, c, dim=-1)).sum(-1)
    den = la * lb * lc + (a * b).sum(-1) * lc + (b * c).sum(-1) * la + (c * a).sum(-1) * lb
    return (2 * torch.atan2(det, den)).sum(1) / (4 * np.pi)


@pytest.mark.parametrize("kind", sorted(SHOE_KINDS))
def test_shoe_is_a_closed_outward_shell_around_the_foot(anny_body, kind):
    pts, ankle, toe = _foot(anny_body)
    shoe = shoe_surface(pts, ankle, toe, kind)
    f = shoe.faces
    # Closed: every edge is used by exactly two faces, once in each direction (consistent winding).
    e = torch.cat([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    directed = torch.unique(e, dim=0)
    assert len(directed) == len(e)
    assert len(torch.unique(torch.sort(e, 1).values, dim=0)) * 2 == len(e)
    # Outward: the winding number is +1 at the foot's points below the collar (all of them inside) ...
    k = SHOE_KINDS[kind]
    inside = pts[pts[:, 1] <= float(ankle[1]) + k["collar"]]
    w = _winding(inside, shoe.verts, f)
    assert len(inside) > 50 and float(w.min()) > 0.99 and float(w.max()) < 1.01
    # ... and 0 at points well outside (the knee, a point in front of the toes).
    far = torch.stack([ankle + torch.tensor([0.0, 0.35, 0.0]), toe + 0.12 * (toe - ankle) / (toe - ankle).norm()])
    assert float(_winding(far, shoe.verts, f).abs().max()) < 0.01
    # A flat sole slab: the lowest shoe points lie on one plane `sole` metres under the foot.
    y = shoe.verts[:, 1]
    floor = float(pts[:, 1].min()) - k["sole"]
    assert abs(float(y.min()) - floor) < 1e-5 and int(((y - floor).abs() < 1e-5).sum()) >= 4 * 10
    assert shoe.uv.shape == (len(shoe.verts), 2) and float(shoe.uv.min()) >= 0 and float(shoe.uv.max()) <= 1


def test_shoe_refuses_bad_input(anny_body):
    pts, ankle, toe = _foot(anny_body)
    with pytest.raises(InputError, match="kind"):
        shoe_surface(pts, ankle, toe, "clog")
    with pytest.raises(InputError, match="collar"):
        shoe_surface(pts + torch.tensor([0.0, 5.0, 0.0]), ankle, toe)
