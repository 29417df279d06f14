"""The real-people encoder of the CNN: the shipped pose network's trunk, projected onto the CNN's levels.

MediaPipe's pose network (``person_pose.onnx``, trained on photographs of real people; it reads a
256² crop of a person, the CNN's own framing) runs as a torch module (:mod:`.onnx_torch`). Its
feature maps at strides 2 … 32 of an input at twice the CNN's size land on the CNN's levels
(strides 1 … 16); each is projected to that level's width by a 1×1 convolution that starts at
zero, so a new network starts as the plain CNN and learns how much of the real-people features to
use.

The pose weights stay frozen (``train_after=None``) or thaw after one of its taps
(:func:`.onnx_torch.pose_encoder`). Frozen weights are the package's own file: they are left out of
the network's state dict (a checkpoint holds only what training changed) and put back from the
file on load.
"""

from __future__ import annotations

import torch
from torch import nn
from torch.nn import functional as F

from ..checks import ShapeError
from .onnx_torch import POSE_TAPS, pose_encoder

__all__ = ["PoseFeatures"]


class PoseFeatures(nn.Module):
    """Projected pose-network features for the CNN's levels.

    Args:
        widths: the CNN's channel count per level (level i at stride 2**i), at most five levels.
        train_after: None (frozen) or a stride of :data:`~.onnx_torch.POSE_TAPS` after which the
            pose network's weights train.
        upsample: 2 (the pose network reads the input at twice its size: the CNN's own input) or 1
            (it reads it as it is: a CNN at half resolution, ``NetConfig.work_scale`` 2, given the full one).

    ``forward(x)``: x (B, 4, H, W) from :func:`~relightnet.model.normalize_input` (H, W multiples of
    16 · 2 / upsample) -> a list of (B, widths[i], H · upsample / 2**(i + 1), W · upsample / 2**(i + 1)).
    """

    def __init__(self, widths: list[int], train_after: int | None = None, upsample: int = 2) -> None:
        super().__init__()
        if len(widths) > len(POSE_TAPS):
            raise ShapeError(f"widths: the pose network has {len(POSE_TAPS)} levels, got {len(widths)}")
        if upsample not in (1, 2):
            raise ShapeError(f"upsample: expected 1 or 2, got {upsample!r}")
        self.upsample = upsample
        taps = POSE_TAPS[: len(widths)]
        self.encoder = pose_encoder([t.name for t in taps], train_after=train_after)
        self.proj = nn.ModuleList(nn.Conv2d(t.channels, w, 1) for t, w in zip(taps, widths, strict=True))
        for p in self.proj:
            nn.init.zeros_(p.weight)
            nn.init.zeros_(p.bias)
        self._frozen = {f"encoder.{k}" for k, v in self.encoder.named_parameters() if not v.requires_grad}
        self.register_state_dict_post_hook(_drop_frozen)
        self.register_load_state_dict_pre_hook(_restore_frozen)

    def forward(self, x: torch.Tensor) -> list[torch.Tensor]:
        if x.dim() != 4 or x.shape[1] != 4:
            raise ShapeError(f"input: expected (B, 4, H, W) from normalize_input, got {tuple(x.shape)}")
        person = ((x[:, :3] + x[:, 3:4]) / 2).float()  # the sRGB person on black, in [0, 1]
        up = person if self.upsample == 1 else F.interpolate(person, scale_factor=2, mode="bilinear",
                                                             align_corners=False)
        trains = any(p.requires_grad for p in self.encoder.parameters())
        with torch.set_grad_enabled(trains and torch.is_grad_enabled()):
            feats = self.encoder(up)
        return [proj(f.to(proj.weight.dtype)) for proj, f in zip(self.proj, feats, strict=True)]


def _drop_frozen(module: PoseFeatures, state_dict: dict, prefix: str, local_metadata) -> None:
    for key in module._frozen:
        state_dict.pop(prefix + key, None)


def _restore_frozen(module: PoseFeatures, state_dict: dict, prefix: str, local_metadata, strict, missing_keys,
                    unexpected_keys, error_msgs) -> None:
    params = dict(module.named_parameters())
    for key in module._frozen:
        state_dict.setdefault(prefix + key, params[key].detach())
