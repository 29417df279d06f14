"""The 2D path's CNN: network, losses, checkpoints, training loop, inference on real images."""

from .checkpoint import SHIPPED, load_checkpoint, load_model, save_checkpoint, shipped_checkpoint
from .inference import CropBox, estimate_light, mask_crop_box, predict_image
from .losses import LossWeights, erode, masked_l1, relight_losses, total_variation
from .network import (
    NetConfig,
    Prediction,
    RelightNet,
    normalize_input,
    pad_to_multiple,
    photo_albedo,
    relight,
    shading_map,
)

__all__ = [
    "SHIPPED", "load_checkpoint", "load_model", "save_checkpoint", "shipped_checkpoint",
    "CropBox", "estimate_light", "mask_crop_box", "predict_image",
    "LossWeights", "erode", "masked_l1", "relight_losses", "total_variation",
    "NetConfig", "Prediction", "RelightNet", "normalize_input", "pad_to_multiple", "photo_albedo", "relight",
    "shading_map",
]
