"""The person stage of the generator: body, pose, painted look, garments and their PRT, once per pose.

A posed, clothed person's per-vertex transport does not depend on the camera or the light;
it depends on the view only through a rotation. :func:`person_stage` builds the clothed
mesh in the posed body's world frame (y up, before the sample's yaw) and
:func:`person_transport` its PRT there; a sample then turns it into its camera's light frame
(:func:`transport_to_camera`): with Q the world → camera rotation, the transport of a vertex
is a function on the sphere, so ``T_cam = T_world Mᵀ`` with M the SH rotation matrix of Q
(:func:`relightnet.sh.rotation.sh_rotation_matrix`). This equals the PRT computed in the camera frame
with the direction set turned by Q — again a randomly rotated Fibonacci set — so the ground
truth stays exact (image = albedo ⊙ (T · L) with the T stored).

Stills: ``SynthConfig.prt_reuse`` = G consecutive samples (indices g·G … g·G + G − 1) share
one person stage (body, pose, outfit, garments, PRT directions and bounce flag drawn from
the *group's* seed, :func:`group_seed`); each draws its own yaw, camera, light, background
and noise from its own seed. Clips are their own group (the pose changes every frame).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import torch

from ..checks import InputError
from ..prt import PrtSettings, refined_transport, vertex_transport
from ..raster.texture import texture_pixels
from ..sh.frames import rotation_world_to_light
from ..sh.rotation import sh_rotation_matrix
from .clothed import ClothedMesh, clothed_mesh
from .config import SPLITS, SynthConfig
from .garments import garment_probs, sample_garments
from .poses import sample_phenotype, sample_pose
from .sample import SynthAssets
from .textures import paint_albedo, sample_outfit

__all__ = ["GROUP_KEY", "PersonStage", "group_seed", "person_stage", "person_transport", "seen_vertices",
           "transport_to_camera", "vertex_colors"]

#: The group seed sequence of stills is ``SeedSequence([seed, split, group, GROUP_KEY])``.
GROUP_KEY = 7


def group_seed(cfg: SynthConfig, split: str, index: int) -> tuple[np.random.SeedSequence, int, int]:
    """(seed sequence of the group of still ``index``, group number, member number) for ``cfg.prt_reuse``."""
    g, j = divmod(int(index), int(cfg.prt_reuse))
    return np.random.SeedSequence([cfg.seed, SPLITS.index(split), g, GROUP_KEY]), g, j


@dataclass(frozen=True, eq=False)
class PersonStage:
    """A posed, dressed person in its world frame, and its PRT once computed.

    Attributes:
        mesh: the :class:`~relightnet.data.clothed.ClothedMesh` (T frames).
        joints: (T, J, 3) posed joints. phenotype, pose, outfit, garments: what was drawn.
        regions: (V', R) region field. dir_seed: PRT direction seed. bounce: one interreflection.
        transport, transport_unoccluded: (T, V', K) world-frame PRT, or None before
            :func:`person_transport`.
    """

    mesh: ClothedMesh
    joints: torch.Tensor
    phenotype: dict
    pose: dict
    outfit: dict
    garments: dict
    dir_seed: int
    bounce: bool
    transport: torch.Tensor | None = None
    transport_unoccluded: torch.Tensor | None = None


def person_stage(cfg: SynthConfig, r: dict, assets: SynthAssets, T: int) -> PersonStage:
    """Draw the body, pose, albedo, garments and prt streams of ``r`` and dress the posed body (no PRT yet)."""
    body = assets.body
    phen = sample_phenotype(r["body"], cfg.ages)
    params, pose_desc = sample_pose(r["pose"], n_frames=T)
    outfit = sample_outfit(r["albedo"])
    g = sample_garments(r["garments"], garment_probs(cfg.garment_probs), outfit)
    dir_seed = int(r["prt"].integers(2**31 - 1))
    bounce = bool(r["prt"].uniform() < cfg.bounce_prob)
    with torch.no_grad():
        out = body(pose=params["pose"], trans=params["trans"], phenotype=phen)
    hair = "none" if outfit["hair"] is None else "short"
    field = assets.region_field(outfit["sleeves"], outfit["legs"], hair)
    tex = paint_albedo(assets.atlas, field, outfit, assets.texel_regions(outfit["sleeves"], outfit["legs"], hair))
    mesh = clothed_mesh(g, outfit, out.verts.detach(), out.normals.detach(), out.joints.detach(), body,
                        assets.garment_tables(), tex, field, assets.atlas)
    return PersonStage(mesh, out.joints.detach(), phen, pose_desc, outfit, {**g, "types": mesh.types}, dir_seed,
                       bounce)


def vertex_colors(mesh: ClothedMesh) -> torch.Tensor:
    """(V', 3) the texture's albedo at every vertex (at its UV in the first face that uses it)."""
    idx = torch.zeros(mesh.verts.shape[1], dtype=torch.int64)
    used, first = np.unique(mesh.faces.flatten().numpy(), return_index=True)
    idx[torch.as_tensor(used)] = mesh.uv_faces.flatten()[torch.as_tensor(first)]
    tex = mesh.tex.permute(2, 0, 1)[None]
    return texture_pixels(tex, mesh.uv[idx], check=False)


def person_transport(cfg: SynthConfig, person: PersonStage, seen: torch.Tensor | None = None) -> PersonStage:
    """The person with its world-frame PRT (every frame; occluded, with the bounce if drawn, and unoccluded).

    Without a bounce, vertices hidden under garments on every side (``mesh.hidden``) are not
    ray cast (transport 0: a pixel never shows them unless the body pokes through the cloth),
    nor, when ``seen`` is given, the vertices no pixel of the samples that use this PRT shows.
    The midpoints of the garments' subdivided outer sides are ray cast only at shadow edges
    (:func:`relightnet.prt.refined_transport`).

    Args:
        cfg: the config. person: from :func:`person_stage`.
        seen: None, or (T, V') bool: per frame, the vertices of the faces some pixel shows
            (:func:`seen_vertices`). The rows of those vertices equal the rows computed without
            ``seen`` bit for bit (a vertex's transport does not depend on which others are cast);
            the others are 0. Ignored with a bounce, which gathers light from every vertex.
    """
    m = person.mesh
    T, V = m.verts.shape[:2]
    if seen is not None:
        seen = torch.as_tensor(seen, dtype=torch.bool)
        if seen.shape != (T, V):
            raise InputError(f"seen: expected ({T}, {V}) bool, got {tuple(seen.shape)}")
    prt = PrtSettings(n_dirs=cfg.n_dirs, seed=person.dir_seed, threads=torch.get_num_threads())
    kw = dict(lmax=cfg.lmax, manifold="ignore")
    grey = vertex_colors(m).mean(1) if person.bounce else None
    occ, un = [], []
    for t in range(T):
        v, n = m.verts[t], m.normals[t]
        keep = None
        if not person.bounce:
            keep = torch.nonzero(~m.hidden if seen is None else ~m.hidden & seen[t]).flatten()
        occ.append(refined_transport(v, m.faces, n, m.midpoints, prt=dataclasses.replace(prt,
                                                                                         bounces=int(person.bounce)),
                                     albedo=grey, vertices=keep, **kw))
        un.append(vertex_transport(v, m.faces, n, prt=dataclasses.replace(prt, occlusion=False), **kw))
    return dataclasses.replace(person, transport=torch.stack(occ), transport_unoccluded=torch.stack(un))


def seen_vertices(faces: torch.Tensor, n_verts: int, frags) -> torch.Tensor:
    """(V,) bool: the vertices some pixel of ``frags`` shows (the union of each one's
    :meth:`~relightnet.raster.Fragments.seen_vertices`; e.g. every view that will use one PRT)."""
    out = torch.zeros(n_verts, dtype=torch.bool)
    for fr in frags:
        out[fr.seen_vertices(faces, n_verts)] = True
    return out


def transport_to_camera(transport: torch.Tensor, world_to_camera: torch.Tensor, lmax: int) -> torch.Tensor:
    """Turn world-frame transport (..., V, K) into the light frame of a camera with rotation (3, 3) world → camera."""
    if transport.shape[-1] != (lmax + 1) ** 2:
        raise InputError(f"transport: expected K = {(lmax + 1) ** 2} coefficients, got {transport.shape[-1]}")
    M = sh_rotation_matrix(rotation_world_to_light(world_to_camera.double()), lmax)
    return (transport.double() @ M.T).float()
