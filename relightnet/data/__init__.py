"""Synthetic data with exact ground truth: configuration, sample generator, shards, Dataset, augmentation.

The public names are what makes and reads a dataset: the configuration (:class:`SynthConfig`,
:func:`load_config`), the generator (:func:`generate_sample` → :class:`Sample`, :func:`generate_samples`,
:func:`generate_sequence`, :func:`run_synth`), the shards (:func:`write_shard`, :func:`read_shard`,
:func:`load_manifest`, :func:`verify_dataset`), :class:`SynthDataset`, :class:`Augment` and
:func:`preview`. The scene's parts (lights, garments, framing, render) stay in their modules.

The shipped CC0 environment maps live in ``envmaps/``."""

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
