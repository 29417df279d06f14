"""What the avatar's outfits add to the generator's clothes: shoes, and hems cut along smooth lines.

- **Shoes** (:class:`ShoeRig`): a closed shoe around each foot
  (:func:`relightnet.body.shoes.shoe_surface`, built once on the rest body) that poses with the
  body: every shoe vertex blends the rigid motions of the foot, the toes and the lower leg
  (linear blend skinning, each bone's motion the least-squares rotation and translation of the
  body vertices it dominates, :func:`relightnet.fit.init.kabsch`), so the shoe follows the foot
  through a walk. Its texture panel (:func:`shoe_panel`) is painted in rows of height: the sole,
  a welt, the upper.
- **Smooth hems** (:class:`HemCut`): the generator's shells copy whole body faces, so their open
  borders (necklines, sleeve ends, waists, trouser hems, hairlines) follow face edges in a
  stair-step. Each shell is cut instead along an iso-line of a smooth field that is 0 on its border
  and rises inward (:func:`relightnet.body.garments.hem_field`): faces the line crosses keep their
  inside part, with new vertices on the crossed edges (:func:`relightnet.body.garments.iso_clip`),
  so the hem is a smooth curve through triangles a little inside the old border. A new vertex is a
  fixed blend of two shell vertices, so it follows the body in every frame as they do.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from ..body.base import vertex_normals
from ..body.garments import hem_field, iso_clip
from ..body.shoes import SHOE_KINDS, shoe_surface

__all__ = ["SHOE_UV_HEIGHT", "ShoeRig", "shoe_rig", "shoe_panel", "HemCut", "hem_cut"]

#: Height (metres) the shoe panel's rows span from the sole's bottom up (v = 1 at the top row).
SHOE_UV_HEIGHT = 0.3
#: Sole colours (linear) per shoe kind; None: a darker shade of the upper.
_SOLE = {"sneaker": (0.72, 0.71, 0.68), "boot": (0.025, 0.022, 0.02), "dress_shoe": (0.02, 0.015, 0.012),
         "flat": None}


def _smoothstep(x: torch.Tensor) -> torch.Tensor:
    x = x.clamp(0.0, 1.0)
    return x * x * (3 - 2 * x)


@dataclass(frozen=True, eq=False)
class ShoeRig:
    """Both shoes of a body and how they follow it.

    Attributes:
        rest: (Vs, 3) float32 rest positions (left shoe, then right). faces: (Fs, 3) into them.
        uv: (Vs, 2) float32 (s along the foot, height / :data:`SHOE_UV_HEIGHT`).
        bones: per bone, the (P,) int64 body vertices it dominates. weights: (Vs, B) float32 skinning weights.
        kind: the shoe kind (:data:`~relightnet.body.shoes.SHOE_KINDS`).
    """

    rest: torch.Tensor
    faces: torch.Tensor
    uv: torch.Tensor
    bones: list
    weights: torch.Tensor
    kind: str

    def pose(self, rest_body: torch.Tensor, body: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """The shoes on posed bodies: (verts, normals) (T, Vs, 3) for body positions (T, V, 3) (rest: (V, 3))."""
        from ..fit.init import kabsch

        T = body.shape[0]
        x = torch.zeros(T, self.rest.shape[0], 3, dtype=torch.float64)
        for b, idx in enumerate(self.bones):
            p, q = rest_body[idx].double(), body[:, idx].double()
            R = kabsch(p.expand(T, -1, -1), q, torch.ones(T, len(idx), dtype=torch.float64))
            moved = (self.rest.double() - p.mean(0)) @ R.transpose(1, 2) + q.mean(1, keepdim=True)
            x += self.weights[:, b, None].double() * moved
        x = x.float()
        return x, torch.stack([vertex_normals(v, self.faces) for v in x])


def shoe_rig(body, rest_verts: torch.Tensor, rest_joints: torch.Tensor, kind: str) -> ShoeRig:
    """Build both shoes of kind ``kind`` around an Anny ``body``'s feet at rest ((V, 3) verts, (J, 3) joints)."""
    names = list(body.joint_names)
    w = body.anny.vertex_bone_weights.detach().cpu()
    bi = body.anny.vertex_bone_indices.detach().cpu().long()
    dom = np.array(names)[bi.gather(1, w.argmax(1, keepdim=True))[:, 0].numpy()]
    rest, faces, uvs, bones, weights, n = [], [], [], [], [], 0
    for side in "LR":
        foot = np.flatnonzero(dom == f"foot.{side}")
        toes = np.flatnonzero(np.char.startswith(dom, "toe") & np.char.endswith(dom, f".{side}"))
        leg = np.flatnonzero(np.char.startswith(dom, "lowerleg") & np.char.endswith(dom, f".{side}"))
        ankle = rest_joints[names.index(f"foot.{side}")]
        toe = rest_joints[[names.index(f"toe{k}-1.{side}") for k in range(1, 6)]].mean(0)
        pts = rest_verts[np.concatenate([foot, toes, leg])]
        piece = shoe_surface(pts, ankle, toe, kind)
        ax = toe - ankle
        ax[1] = 0.0
        ax = ax / ax.norm()
        s = (piece.verts - toe) @ ax
        w_leg = _smoothstep((piece.verts[:, 1] - float(ankle[1]) - 0.03) / 0.06)
        w_toe = _smoothstep((s + 0.01) / 0.03) * (1 - w_leg)
        wb = torch.zeros(len(piece.verts), 6)
        wb[:, len(bones):len(bones) + 3] = torch.stack([1 - w_toe - w_leg, w_toe, w_leg], 1)
        bones += [torch.as_tensor(foot), torch.as_tensor(toes), torch.as_tensor(leg)]
        rest.append(piece.verts)
        faces.append(piece.faces + n)
        y0 = float(piece.verts[:, 1].min())
        uvs.append(torch.stack([piece.uv[:, 0], ((piece.verts[:, 1] - y0) / SHOE_UV_HEIGHT).clamp(0, 1)], 1))
        weights.append(wb)
        n += len(piece.verts)
    return ShoeRig(torch.cat(rest), torch.cat(faces), torch.cat(uvs).float(), bones, torch.cat(weights), kind)


def shoe_panel(size: int, kind: str, color) -> torch.Tensor:
    """(S, S, 3) linear texture of a shoe: rows of height (row 0 = v = 1 = :data:`SHOE_UV_HEIGHT` above the
    sole's bottom): the sole up to its thickness, a 3 mm welt, then the upper in ``color`` (3,) linear."""
    up = torch.as_tensor(np.asarray(color, dtype=np.float32)).clamp(0.02, 0.9)
    sole = up * 0.45 if _SOLE[kind] is None else torch.tensor(_SOLE[kind])
    h = (1 - (torch.arange(size, dtype=torch.float32) + 0.5) / size) * SHOE_UV_HEIGHT  # metres, per row
    t = SHOE_KINDS[kind]["sole"]
    row = torch.where((h < t)[:, None], sole, torch.where((h < t + 0.003)[:, None], up * 0.55, up))
    return row[:, None, :].expand(size, size, 3).contiguous()


@dataclass(frozen=True, eq=False)
class HemCut:
    """The dressed mesh with its shells' borders cut along smooth lines (module docstring).

    Attributes:
        faces: (F', 3) faces (the kept faces first, in their order; body faces are never cut).
        edges: (E, 2) int64 the two vertices each new vertex lies between. t: (E,) its place on that edge.
        uv_faces: (F', 3) the matching UV faces. uv: (Vt + E', 2) the UVs with the cut's new ones.
    """

    faces: torch.Tensor
    edges: torch.Tensor
    t: torch.Tensor
    uv_faces: torch.Tensor
    uv: torch.Tensor

    def apply(self, verts: torch.Tensor, normals: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(V, 3) positions and normals of the uncut mesh → (V + E, 3) with the new vertices appended."""
        a, b, t = self.edges[:, 0], self.edges[:, 1], self.t[:, None]
        n = (1 - t) * normals[a] + t * normals[b]
        return (torch.cat([verts, (1 - t) * verts[a] + t * verts[b]]),
                torch.cat([normals, n / n.norm(dim=1, keepdim=True).clamp_min(1e-9)]))


def hem_cut(faces: torch.Tensor, verts: torch.Tensor, uv: torch.Tensor, uv_faces: torch.Tensor, shells: list,
            midpoints: torch.Tensor | None = None, level: float = 0.5) -> HemCut:
    """Cut the shells of a dressed mesh along iso-lines of :func:`~relightnet.body.garments.hem_field`.

    Args:
        faces: (F, 3) the dressed mesh. verts: (V, 3) its rest positions. uv: (Vt, 2), uv_faces: (F, 3) its UVs.
        shells: (first vertex, vertex count, reach) of each piece to cut (the field is read off its faces that
            lie in that range, e.g. a two-sided piece's inner side when its outer side is subdivided).
        midpoints: (M, 3) rows (vertex, endpoint a, endpoint b) of vertices added at edge midpoints (a
            subdivided outer side, :class:`~relightnet.body.subdivide.SubdividedFaces`): their field is the mean of
            their endpoints'.
        level: the iso-value of the fields (:func:`~relightnet.body.garments.hem_field`): the hem lies
            ``level · reach`` border edge lengths inside the old border.
    """
    n_verts = verts.shape[0]
    field = torch.ones(n_verts)
    for start, count, reach in shells:
        own = ((faces >= start) & (faces < start + count)).all(1)
        field[start:start + count] = hem_field(faces[own] - start, verts[start:start + count], reach)
    if midpoints is not None and len(midpoints):
        field[midpoints[:, 0]] = 0.5 * (field[midpoints[:, 1]] + field[midpoints[:, 2]])
    corner = field[faces]
    f2, edges, t = iso_clip(faces, corner, level, n_verts)
    uf2, uv_edges, uv_t = iso_clip(uv_faces, corner, level, len(uv))
    a, b = uv_edges[:, 0], uv_edges[:, 1]
    new_uv = (1 - uv_t[:, None]) * uv[a] + uv_t[:, None] * uv[b]
    return HemCut(f2, edges, t, uf2, torch.cat([uv, new_uv]))
