"""The 2D path's CNN: network, its maps in the CNN layout, the photo albedo, losses, checkpoints, training
loop, inference on real images.

The public names are what a user of the network needs: the network and its configuration and
prediction (:class:`RelightNet`, :class:`NetConfig`, :class:`Prediction`, :func:`normalize_input`), the
checkpoints (:func:`load_model`, the shipped one; :func:`load_checkpoint`, :func:`save_checkpoint`), inference
on a photo (:func:`predict_image`, :func:`estimate_light`), the maps' helpers in the CNN layout
(:func:`relight`, :func:`shading_map`, :func:`shade_map`, :func:`pad_to_multiple`), the photo albedo, the
pose-model encoder (:func:`pose_encoder`, :data:`POSE_TAPS`) and the training loss
(:func:`relight_losses`, :class:`LossWeights`). Training, evaluation, ONNX export and serving, the crops
and the exposure helpers stay in their modules (:mod:`.training`, :mod:`.onnx_export`, :mod:`.inference`, ...).

Example:
    A small network (the shipped one is :func:`load_model`) on one normalised 32 × 32 input:

    >>> import torch
    >>> from relightnet.model import NetConfig, RelightNet, normalize_input
    >>> net = RelightNet(NetConfig(width=8, max_width=16, levels=2, light_hidden=16)).eval()
    >>> x = normalize_input(torch.rand(1, 3, 32, 32), torch.ones(1, 1, 32, 32))
    >>> x.shape
    torch.Size([1, 4, 32, 32])
    >>> with torch.no_grad():
    ...     pred = net(x)
    >>> pred.albedo.shape, pred.transport.shape, pred.light.shape, pred.mask.shape
    (torch.Size([1, 3, 32, 32]), torch.Size([1, 9, 32, 32]), torch.Size([1, 9, 3]), torch.Size([1, 1, 32, 32]))
"""

from .checkpoint import load_checkpoint, load_model, save_checkpoint, shipped_checkpoint
from .inference import estimate_light, predict_image
from .losses import LossWeights, relight_losses
from .maps import pad_to_multiple, relight, shade_map, shading_map
from .network import NetConfig, Prediction, RelightNet, normalize_input
from .onnx_torch import POSE_TAPS, pose_encoder
from .photo_albedo import photo_albedo

__all__ = [
    "load_model", "load_checkpoint", "save_checkpoint", "shipped_checkpoint", "RelightNet", "NetConfig", "Prediction",
    "normalize_input", "predict_image", "estimate_light", "relight", "shading_map", "shade_map", "pad_to_multiple",
    "photo_albedo", "POSE_TAPS", "pose_encoder", "relight_losses", "LossWeights",
]
