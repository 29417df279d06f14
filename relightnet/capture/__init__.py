"""A filmed person as an avatar: geometry beyond the body, a de-lit albedo texture, the avatar file.

The fitted body of every frame (:mod:`relightnet.fit`) is grown by per-vertex offsets along its
normals (:mod:`.offsets`; :func:`~relightnet.capture.offsets.solve_offsets` finds them from the
masks), every frame's visible texels are divided by the shading of that geometry under the frame's
light and fused over the frames (:mod:`.texture`, :mod:`.fuse`), texels never seen are filled
(:mod:`.fill`), and the result is one versioned file of arrays (:mod:`.avatar_file`) that
:class:`CapturedBody` poses and renders.

The public names are that job (:func:`capture_person` → :class:`CaptureResult`, with
:class:`TextureOptions`), the avatar file (:func:`save_avatar`, :func:`load_avatar`,
:class:`CapturedAvatar`) and :class:`CapturedBody`; the offsets, the metrics and the generated ground
truth (:mod:`.metrics`, :mod:`.truth`) stay in their modules."""

from .avatar_file import CapturedAvatar, load_avatar, save_avatar
from .body import CapturedBody
from .fuse import CaptureResult, capture_person
from .texture import TextureOptions

__all__ = [
    "CapturedAvatar", "load_avatar", "save_avatar", "CapturedBody", "capture_person", "CaptureResult", "TextureOptions",
]
