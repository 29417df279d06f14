"""The captured person as a body to pose and render: Anny with the captured shape, offsets and texture."""

from __future__ import annotations

from collections.abc import Mapping

from ..checks import InputError
from .avatar_file import CapturedAvatar
from .offsets import apply_offsets

__all__ = ["CapturedBody"]


class CapturedBody:
    """Anny wearing a capture: called like the body model, it poses the body with the captured
    phenotype (whatever phenotype the parameters carry) and moves every vertex along its posed normal
    by the captured offset, so the captured clothes and hair pose with the body.

    Args:
        body: the :class:`~relightnet.body.AnnyBody` the avatar was captured on (same vertex count).
        avatar: the :class:`~relightnet.capture.avatar_file.CapturedAvatar`.

    Attributes:
        body, avatar; faces (F, 3), uv, uv_faces: the body's; num_verts: V;
        albedo: the captured :class:`~relightnet.render.TexturedAlbedo` (S, S, 3).
    """

    def __init__(self, body, avatar: CapturedAvatar) -> None:
        from ..render.frame import TexturedAlbedo

        if body.num_verts != avatar.offsets.numel():
            raise InputError(f"avatar: captured on a body of {avatar.offsets.numel()} vertices, this body has "
                             f"{body.num_verts}")
        self.body, self.avatar = body, avatar
        self.faces, self.uv, self.uv_faces = body.faces, body.uv, body.uv_faces
        self.num_verts = body.num_verts
        self.albedo = TexturedAlbedo(avatar.texture, body.uv, body.uv_faces)
        self._phenotype = avatar.phenotype.to(body.dtype)[None]

    def __call__(self, params: Mapping | None = None, **kwargs):
        """Pose it: the body model's parameters (``pose`` (B, J, 3), ``trans`` (B, 3); a ``phenotype``
        given is replaced by the captured one). Returns a :class:`~relightnet.body.BodyOutput`."""
        from ..body.base import BodyOutput, vertex_normals

        p = dict(params or {}, **kwargs)
        p["phenotype"] = self._phenotype
        out = self.body(p)
        verts = apply_offsets(out.verts, out.normals, self.avatar.offsets)
        return BodyOutput(verts, out.faces, out.uv, out.uv_faces, vertex_normals(verts, out.faces), out.joints,
                          out.joint_names)
