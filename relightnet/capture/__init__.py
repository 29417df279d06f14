"""A filmed person as an avatar: geometry beyond the body, a de-lit albedo texture, the avatar file.

The fitted body of every frame (:mod:`relightnet.fit`) is grown by per-vertex offsets along its
normals (:mod:`.offsets`; :func:`solve_offsets` finds them from the masks), every frame's visible texels are divided by the shading of that
geometry under the frame's light and fused over the frames (:mod:`.texture`, :mod:`.fuse`), texels
never seen are filled (:mod:`.fill`), and the result is one versioned file of arrays
(:mod:`.avatar_file`) that :class:`CapturedBody` poses and renders.
"""

from .avatar_file import AVATAR_SUFFIX, CapturedAvatar, load_avatar, save_avatar
from .body import CapturedBody
from .fuse import CaptureResult, capture_person
from .metrics import (
    HIDDEN_PARTS,
    albedo_error,
    light_invariance,
    person_psnr,
    person_ssim,
    seen_share,
    silhouette_iou,
    surface_texels,
)
from .offsets import OffsetFit, apply_offsets, solve_offsets
from .texture import TextureOptions
from .truth import TruthClip, light_pair, person_texture, truth_phenotype, turning_params, turning_person

__all__ = ["AVATAR_SUFFIX", "CapturedAvatar", "load_avatar", "save_avatar", "CapturedBody", "CaptureResult",
           "capture_person", "OffsetFit", "apply_offsets", "solve_offsets", "TextureOptions"]
__all__ += ["HIDDEN_PARTS", "albedo_error", "light_invariance", "person_psnr", "person_ssim", "seen_share",
            "silhouette_iou", "surface_texels"]
__all__ += ["TruthClip", "light_pair", "person_texture", "truth_phenotype", "turning_params", "turning_person"]
