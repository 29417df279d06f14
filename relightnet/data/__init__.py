"""Synthetic data: configuration, sample generator, shards, Dataset (and the shipped env maps in envmaps/)."""

from .config import HDRI_NAMES, SPLITS, SynthConfig, load_config, sample_seed

__all__ = ["HDRI_NAMES", "SPLITS", "SynthConfig", "load_config", "sample_seed"]
