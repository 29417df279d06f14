"""The 3D-path frame renderer: mesh + per-vertex transport + albedo + light + camera → image and maps.

Shading is linear in the transport, so ``S_v = T_v · L`` is computed once per vertex and
interpolated (3 channels instead of K); albedo is applied per pixel (texture lookup or
interpolated vertex colour). This equals interpolating T and shading per pixel exactly.
The K-channel transport map is interpolated only when ``maps=True`` asks for it.

Lights estimated from an image are relative to that image's camera (docs/design.md, "Frames"). With
``light_frame="camera"`` (the default) the light is rotated into the world's light frame
by the camera rotation; for the default camera (R = I) this is the identity.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import torch

from ..checks import InputError, check_sh_count, check_shape
from ..raster import Camera, Fragments, Window, interpolate, rasterize
from ..raster.interpolate import interpolate_pixels
from ..raster.texture import texture_pixels
from ..sh import rotate_sh
from ..sh.frames import rotation_world_to_light
from .shading import shading

__all__ = ["TexturedAlbedo", "RenderOutput", "light_in_world", "render_mesh"]


@dataclass(frozen=True, eq=False)
class TexturedAlbedo:
    """A UV-mapped albedo.

    Attributes:
        tex: (Ht, Wt, 3) or (B, Ht, Wt, 3) linear RGB texture (row 0 = v = 1).
        uv: (Vt, 2) texture coordinates, v up.
        uv_faces: (F, 3) indices into ``uv``, one row per mesh face.
    """

    tex: torch.Tensor
    uv: torch.Tensor
    uv_faces: torch.Tensor


@dataclass(frozen=True, eq=False)
class RenderOutput:
    """What :func:`render_mesh` returns (channels-last, linear RGB).

    (H, W) is the frame's size, or the window's when one was rendered (``frags.window``: where it lies
    in the frame).

    Attributes:
        pix_image: (N, 3) shaded radiance of the N covered pixels (at ``frags.pix``, in its order).
        frags: the :class:`~relightnet.raster.Fragments`.
        transport: (B, H, W, K) (or (B, H, W, K, 3) for per-channel transport), when maps were asked.
        albedo: (B, H, W, 3), when maps were asked.
        normals: (B, H, W, 3) unit world-frame normals (0 on background), when maps were asked.
        depth: (B, H, W) distance in front of the camera (+inf on background), when maps were asked.
        shading: (B, H, W, 3) S = T·L, when maps were asked.

    Dense views, built on first access and cached (a caller that composites the covered pixels only
    never makes them):

    - ``image`` (B, H, W, 3) shaded radiance, 0 on background;
    - ``alpha`` (B, H, W) coverage in {0, 1}, in ``pix_image``'s dtype.
    """

    pix_image: torch.Tensor
    frags: Fragments
    transport: torch.Tensor | None = None
    albedo: torch.Tensor | None = None
    normals: torch.Tensor | None = None
    depth: torch.Tensor | None = None
    shading: torch.Tensor | None = None

    @cached_property
    def image(self) -> torch.Tensor:
        """(B, H, W, 3) shaded radiance, 0 on background."""
        B, H, W = self.frags.shape
        x = self.pix_image
        return torch.zeros(B * H * W, 3, dtype=x.dtype, device=x.device).index_copy(0, self.frags.pix, x).view(
            B, H, W, 3)

    @cached_property
    def alpha(self) -> torch.Tensor:
        """(B, H, W) coverage in {0, 1}."""
        return self.frags.mask.to(self.pix_image.dtype)


def light_in_world(light: torch.Tensor, camera: Camera) -> torch.Tensor:
    """Rotate camera-relative SH lights into the world's light frame.

    Args:
        light: (K, 3) or (B, K, 3) lights relative to each camera's view frame.
        camera: B cameras; ``camera.R`` is world→camera.

    Returns:
        (B, K, 3) lights in the light frame of the world (identity for the default camera).
    """
    check_shape(light, ["...", "K", 3], name="light")
    R = camera.R.to(light.dtype)
    if torch.equal(R, torch.eye(3, dtype=R.dtype, device=R.device).expand_as(R)):
        return light.expand(camera.batch_size, *light.shape[-2:]) if light.dim() == 2 else light
    return rotate_sh(light, rotation_world_to_light(R.transpose(1, 2)))


def _batched(x: torch.Tensor, b: int, tail: list, name: str, v: int) -> torch.Tensor:
    """Accept ``tail`` or ``(B, *tail)`` shapes, with the vertex count pinned to ``v``."""
    check_shape(x, tail if x.dim() == len(tail) else [b, *tail], name=name, dims={"V": v})
    return x


def render_mesh(
    verts: torch.Tensor,
    faces: torch.Tensor,
    transport: torch.Tensor,
    albedo: torch.Tensor | TexturedAlbedo,
    light: torch.Tensor,
    camera: Camera,
    normals: torch.Tensor | None = None,
    light_frame: str = "camera",
    maps: bool = False,
    frags: Fragments | None = None,
    window: Window | None = None,
) -> RenderOutput:
    """Render a mesh with precomputed per-vertex transport under an SH light.

    Args:
        verts: (V, 3) or (B, V, 3) world-frame positions.
        faces: (F, 3) int64 triangles.
        transport: (V, K) or (B, V, K) per-vertex transport (``relightnet.prt.vertex_transport``),
            or per-channel (V, K, 3) / (B, V, K, 3) after coloured interreflection.
        albedo: (V, 3) / (B, V, 3) per-vertex linear albedo, or a :class:`TexturedAlbedo`.
        light: (K, 3) or (B, K, 3) SH light.
        camera: B cameras (``camera.size`` is the frame's size).
        normals: (V, 3) / (B, V, 3) world normals, needed only for the ``normals`` map.
        light_frame: ``"camera"`` (light relative to the camera, docs/design.md) or ``"world"``.
        maps: also return the transport, albedo, normals, depth and shading maps.
        frags: the :class:`Fragments` of ``rasterize(camera.transform(verts), faces, camera.size,
            window=window)`` when already computed (e.g. to find the visible vertices first); None
            rasterizes.
        window: render only this :class:`~relightnet.raster.Window` of the frame (e.g. the mesh's
            :func:`~relightnet.raster.screen_box`): every image is the window's size and holds the
            whole frame's render at those pixels. None: the whole frame.

    Returns:
        :class:`RenderOutput`.
    """
    if light_frame not in ("camera", "world"):
        raise InputError(f"light_frame: expected 'camera' or 'world', got {light_frame!r}")
    check_shape(light, ["...", "K", 3], name="light")
    k = light.shape[-2]
    check_sh_count(light, "light")
    B = camera.batch_size
    per_channel = transport.shape[-1] == 3 and transport.dim() >= 3 and transport.shape[-2] == k
    tail = ["V", k, 3] if per_channel else ["V", k]
    check_shape(verts, ["...", 3], name="verts")
    nv = verts.shape[-2]
    transport = _batched(transport, B, tail, "transport", nv)
    check_shape(faces, ["F", 3], name="faces")
    L = light_in_world(light, camera) if light_frame == "camera" else light
    if L.dim() == 2:
        L = L.expand(B, k, 3)
    check_shape(L, [B, k, 3], name="light")

    if frags is None:
        frags = rasterize(camera.transform(verts), faces, camera.size, window=window)
    elif window is not None and frags.window != window:
        raise InputError(f"frags: rasterized in {frags.window}, not in the window {window} asked for")
    # Per-vertex shading, batched over cameras: (B, V, 3).
    Tb = transport.expand(B, *transport.shape) if transport.dim() == len(tail) else transport
    S_v = torch.stack([shading(Tb[b], L[b]) for b in range(B)])
    S = interpolate_pixels(S_v, frags, faces)  # (N, 3)

    if isinstance(albedo, TexturedAlbedo):  # sampled at the covered pixels only
        uv = interpolate_pixels(albedo.uv.to(S), frags, albedo.uv_faces)
        tex = albedo.tex if albedo.tex.dim() == 4 else albedo.tex[None]
        if tex.shape[0] not in (1, B):
            raise InputError(f"albedo.tex: batch {tex.shape[0]} must be 1 or match the cameras' {B}")
        A = texture_pixels(tex.permute(0, 3, 1, 2).to(S), uv, frags.pix_batch if tex.shape[0] > 1 else None)
    else:
        albedo = _batched(albedo, B, ["V", 3], "albedo", nv)
        A = interpolate_pixels(albedo.to(S), frags, faces)

    return RenderOutput(A * S, frags, **(_maps(Tb, A, S, normals, frags, faces, camera) if maps else {}))


def _maps(Tb, A, S, normals, frags: Fragments, faces, camera: Camera) -> dict:
    """:class:`RenderOutput`'s maps from the (B, V, K[, 3]) transport and the covered pixels' (N, 3)
    albedo and shading."""
    B, H, W = frags.shape
    out = {"transport": interpolate(Tb.reshape(B, Tb.shape[1], -1), frags, faces).view(B, H, W, *Tb.shape[2:])}
    for name, x in (("albedo", A), ("shading", S)):
        out[name] = torch.zeros(B * H * W, 3, dtype=S.dtype, device=S.device).index_copy_(0, frags.pix, x).view(
            B, H, W, 3)
    out["depth"] = camera.depth_to_view(frags.depth)
    if normals is not None:
        out["normals"] = torch.nn.functional.normalize(interpolate(normals.to(S), frags, faces), dim=-1)
    return out
