"""The 2D path's CNN: network, its maps in the CNN layout, the photo albedo, losses, checkpoints, training
loop, inference on real images.

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

from .checkpoint import SHIPPED, load_checkpoint, load_model, save_checkpoint, shipped_checkpoint
from .exposure import exposure_level, exposure_scale, match_exposure, transport_level
from .inference import (
    CropBox,
    CropMaps,
    crop_to_box,
    estimate_light,
    estimate_light_evidence,
    frame_person,
    mask_crop_box,
    paste_from_box,
    paste_rows,
    predict_crop,
    predict_image,
)
from .losses import LossWeights, masked_l1, relight_losses, total_variation
from .maps import pad_to_multiple, relight, shade_map, shading_map
from .network import (
    DEFAULT_INPUT_SIZE,
    LIGHT_MODES,
    TRANSPORT_HEADS,
    NetConfig,
    Prediction,
    RelightNet,
    cone_maps,
    normalize_input,
)
from .onnx_torch import POSE_TAPS, GraphModule, Tap, find_stride_taps, load_onnx, pose_encoder
from .photo_albedo import photo_albedo, photo_albedo_rows

__all__ = [
    "SHIPPED", "load_checkpoint", "load_model", "save_checkpoint", "shipped_checkpoint",
    "exposure_level", "exposure_scale", "match_exposure", "transport_level",
    "CropBox", "CropMaps", "crop_to_box", "estimate_light", "estimate_light_evidence", "frame_person",
    "mask_crop_box", "paste_from_box", "paste_rows", "predict_crop", "predict_image",
    "LossWeights", "masked_l1", "relight_losses", "total_variation",
    "DEFAULT_INPUT_SIZE", "LIGHT_MODES", "TRANSPORT_HEADS", "NetConfig", "Prediction", "RelightNet", "cone_maps",
    "normalize_input", "pad_to_multiple", "photo_albedo", "photo_albedo_rows", "relight", "shade_map", "shading_map",
    "POSE_TAPS", "GraphModule", "Tap", "find_stride_taps", "load_onnx", "pose_encoder",
]
