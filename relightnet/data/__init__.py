"""Synthetic data with exact ground truth: configuration, sample generator, shards, Dataset, augmentation.

The shipped CC0 environment maps live in ``envmaps/``.
"""

from .augment import Augment, crop, hflip, resize, scale_intensity, sh_mirror_signs, white_balance
from .config import HDRI_NAMES, SPLITS, SynthConfig, load_config, sample_seed
from .dataset import DEFAULT_FIELDS, SynthDataset
from .framing import crop_camera
from .garments import DEFAULT_GARMENT_PROBS, GARMENT_TYPES, garment_probs
from .generate import GENERATOR_VERSION, Sample, generate_sample, generate_samples, generate_sequence
from .preview import preview
from .render_sample import ClipGeometry, clip_geometry
from .shards import load_manifest, read_shard, read_shard_meta, verify_dataset, write_shard
from .synth import run_synth

__all__ = [
    "Augment", "crop", "hflip", "resize", "scale_intensity", "sh_mirror_signs", "white_balance",
    "HDRI_NAMES", "SPLITS", "SynthConfig", "load_config", "sample_seed",
    "DEFAULT_FIELDS", "SynthDataset",
    "crop_camera",
    "GENERATOR_VERSION", "Sample", "generate_sample", "generate_samples", "generate_sequence", "ClipGeometry",
    "clip_geometry", "GARMENT_TYPES", "DEFAULT_GARMENT_PROBS", "garment_probs",
    "preview",
    "load_manifest", "read_shard", "read_shard_meta", "verify_dataset", "write_shard",
    "run_synth",
]
