"""The 2D path's CNN: network, losses, checkpoints, training loop, inference on real images."""

from .checkpoint import SHIPPED, load_checkpoint, load_model, save_checkpoint, shipped_checkpoint
from .inference import CropBox, estimate_light, estimate_light_evidence, mask_crop_box, predict_image
from .light_solve import Evidence, light_evidence, pool_evidence, solve_light, spd_solve
from .losses import LossWeights, erode, masked_l1, relight_losses, total_variation
from .network import (
    LIGHT_MODES,
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
    "CropBox", "estimate_light", "estimate_light_evidence", "mask_crop_box", "predict_image",
    "Evidence", "light_evidence", "pool_evidence", "solve_light", "spd_solve",
    "LossWeights", "erode", "masked_l1", "relight_losses", "total_variation",
    "LIGHT_MODES", "NetConfig", "Prediction", "RelightNet", "normalize_input", "pad_to_multiple", "photo_albedo",
    "relight", "shading_map",
]
