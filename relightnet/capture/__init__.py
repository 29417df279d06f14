"""A filmed person as an avatar: geometry beyond the body, a de-lit albedo texture, the avatar file.

The fitted body of every frame (:mod:`relightnet.fit`) is grown by per-vertex offsets along its
normals (:mod:`.offsets`), every frame's visible texels are divided by the shading of that
geometry under the frame's light and fused over the frames (:mod:`.texture`), texels never seen
are filled (:mod:`.fill`), and the result is one versioned file of arrays (:mod:`.avatar_file`).
"""

from .offsets import apply_offsets

__all__ = ["apply_offsets"]
