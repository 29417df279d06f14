"""Synthetic data with exact ground truth: configuration, sample generator, shards, Dataset, augmentation.

The shipped CC0 environment maps live in ``envmaps/``.
"""

from .augment import Augment
from .config import SynthConfig, load_config
from .dataset import SynthDataset
from .generate import generate_sample, generate_samples, generate_sequence
from .preview import preview
from .sample import Sample
from .shards import load_manifest, read_shard, verify_dataset, write_shard
from .synth import run_synth

__all__ = [
    "SynthConfig", "load_config", "SynthDataset", "Augment", "generate_sample", "generate_samples", "generate_sequence",
    "Sample", "run_synth", "load_manifest", "read_shard", "write_shard", "verify_dataset", "preview",
]
