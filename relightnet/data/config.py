"""Configuration of the synthetic data generator (one frozen dataclass, validated).

A config is plain data: it round-trips through JSON/YAML (the dataset manifest stores
it) and, with a seed, fixes every sample bit for bit. Sample ``i`` of split ``s`` draws
its randomness from ``numpy.random.SeedSequence([seed, SPLITS.index(s), i])``, so any
process can make any sample (or shard) independently.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..checks import InputError
from ..io.documents import clip, from_mapping, short

__all__ = ["SPLITS", "HDRI_NAMES", "SynthConfig", "load_config", "sample_seed"]

#: Dataset splits, in the order used to derive seeds.
SPLITS = ("train", "val", "test")

#: Largest sample count per split, shard size and PRT direction count a config may ask for.
MAX_COUNT = 10_000_000

#: The shipped CC0 environment maps (relightnet/data/envmaps).
HDRI_NAMES = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")


@dataclass(frozen=True)
class SynthConfig:
    """Everything that decides what the generator makes.

    Attributes:
        seed: master seed.
        res: output side in pixels (square, a multiple of 16).
        lmax: SH order of lights and transports (K = (lmax+1)²).
        n_dirs: PRT directions for the ground-truth transport.
        shard_size: samples per shard file.
        counts: samples per split, e.g. ``{"train": 1000, "val": 50, "test": 100}``.
        hdri_train / hdri_test: which shipped env maps each split may use; whole maps are
            held out for testing (val uses the train maps).
        synthetic_light_prob: probability of a procedural light (sky + sun, lobes, fills)
            instead of an env map.
        bounce_prob: probability that a sample's ground truth includes one interreflection
            bounce (flagged in its metadata).
        noise_std: std of the additive sensor noise on ``image`` (linear), 0 to disable;
            the noise-free render stays consistent with albedo ⊙ (T·L) (metadata flag).
        partial_crop_prob: probability of a partial-body crop instead of full-body framing.
        pad: padding around the mask's bounding box (fraction of its larger side).
        jitter: random shift/scale of the crop (fraction of the crop side).
        ages: range of Anny's age parameter (default: teens to adults).
        sequence_frames: frames per clip when making sequences (0: still samples).
        light_mix: optional weights of the light sources (``relightnet.data.lights.LIGHT_SOURCES``:
            hdri, sky_sun, lobes, fills, preetham, window, mixture); when given it replaces
            ``synthetic_light_prob``. Empty: the original draw (env maps and three procedural kinds).
        clip_lights: how a clip's light changes: ``random`` (turning, changing level, sometimes a
            switch), ``constant`` (one fixed light) or ``switch`` (fixed lights, one switch half-way);
            the last two make the clips that measure drift and lag.
        garment_probs: clothes and hair as geometry: per slot (``upper``, ``lower``, ``head``, ``hair``)
            the weights of its choices (:data:`relightnet.data.garments.GARMENT_SLOTS`); slots not
            given keep :data:`~relightnet.data.garments.DEFAULT_GARMENT_PROBS`. ``{"upper": {"none": 1},
            "lower": {"none": 1}, "head": {"none": 1}, "hair": {"painted": 1}}`` paints everything.
        prt_reuse: stills per person and pose: G consecutive samples share one posed, clothed body
            and its PRT (turned into each one's camera frame), each with its own view, light,
            background and noise (:mod:`relightnet.data.person`). 1: every sample its own person.
    """

    seed: int = 0
    res: int = 256
    lmax: int = 2
    n_dirs: int = 128
    shard_size: int = 16
    counts: dict = field(default_factory=lambda: {"train": 64, "val": 8, "test": 16})
    hdri_train: tuple = ("city", "courtyard", "forest", "interior", "studio", "sunset")
    hdri_test: tuple = ("night", "sunrise")
    synthetic_light_prob: float = 0.3
    bounce_prob: float = 0.0
    noise_std: float = 0.0
    partial_crop_prob: float = 0.1
    pad: float = 0.05
    jitter: float = 0.03
    ages: tuple = (0.6, 1.0)
    sequence_frames: int = 0
    light_mix: dict = field(default_factory=dict)
    clip_lights: str = "random"
    garment_probs: dict = field(default_factory=dict)
    prt_reuse: int = 4

    def __post_init__(self) -> None:
        try:
            self._validate()
        except InputError:
            raise
        except (TypeError, ValueError, OverflowError) as e:  # a value of the wrong type (a list for a number, ...)
            raise InputError(f"config: a value has the wrong type ({clip(str(e), 160)})") from None

    def _validate(self) -> None:
        def bad(name, expected):
            raise InputError(f"config {name}: expected {expected}, got {short(getattr(self, name))}")

        if not isinstance(self.seed, int) or self.seed < 0:
            bad("seed", "an integer >= 0")
        if not isinstance(self.res, int) or not 16 <= self.res <= 4096 or self.res % 16:
            bad("res", "a multiple of 16 from 16 to 4096")
        if not isinstance(self.lmax, int) or not 0 <= self.lmax <= 8:
            bad("lmax", "an integer in [0, 8]")
        if not isinstance(self.n_dirs, int) or not 8 <= self.n_dirs <= MAX_COUNT:
            bad("n_dirs", f"an integer from 8 to {MAX_COUNT}")
        if not isinstance(self.shard_size, int) or not 1 <= self.shard_size <= MAX_COUNT:
            bad("shard_size", f"an integer from 1 to {MAX_COUNT}")
        if not isinstance(self.counts, dict) or set(self.counts) - set(SPLITS) or any(
            not isinstance(v, int) or not 0 <= v <= MAX_COUNT for v in self.counts.values()
        ):
            bad("counts", f"a mapping from {SPLITS} to integers from 0 to {MAX_COUNT}")
        for name in ("hdri_train", "hdri_test"):
            names = tuple(getattr(self, name))
            object.__setattr__(self, name, names)
            if not names or set(names) - set(HDRI_NAMES):
                bad(name, f"a non-empty list of {HDRI_NAMES}")
        if set(self.hdri_train) & set(self.hdri_test):
            raise InputError(
                f"config hdri_test: maps {sorted(set(self.hdri_train) & set(self.hdri_test))} are also in "
                "hdri_train; test maps must be held out"
            )
        for name in ("synthetic_light_prob", "bounce_prob", "partial_crop_prob"):
            if not 0.0 <= float(getattr(self, name)) <= 1.0:
                bad(name, "a probability in [0, 1]")
        for name in ("noise_std", "pad", "jitter"):
            if not 0.0 <= float(getattr(self, name)) < 1.0:
                bad(name, "a number in [0, 1)")
        ages = tuple(float(a) for a in self.ages)
        object.__setattr__(self, "ages", ages)
        if len(ages) != 2 or not -1 / 3 <= ages[0] <= ages[1] <= 1.0:
            bad("ages", "(low, high) within Anny's age range [-1/3, 1]")
        if not isinstance(self.sequence_frames, int) or not 0 <= self.sequence_frames <= 10000:
            bad("sequence_frames", "an integer from 0 to 10000")
        if self.clip_lights not in ("random", "constant", "switch"):
            bad("clip_lights", "'random', 'constant' or 'switch'")
        if isinstance(self.prt_reuse, bool) or not isinstance(self.prt_reuse, int) or not 1 <= self.prt_reuse <= 64:
            bad("prt_reuse", "an integer from 1 to 64")
        from .garments import garment_probs
        from .lights import LIGHT_SOURCES

        garment_probs(self.garment_probs)

        mix = self.light_mix
        if not isinstance(mix, dict) or set(mix) - set(LIGHT_SOURCES) or any(
            isinstance(v, bool) or not isinstance(v, int | float) or not 0 <= v < math.inf for v in mix.values()
        ) or (mix and not sum(mix.values()) > 0):
            bad("light_mix", f"a mapping from {LIGHT_SOURCES} to finite weights >= 0 (not all 0)")

    @property
    def n_coeffs(self) -> int:
        return (self.lmax + 1) ** 2

    def hdris(self, split: str) -> tuple:
        """The env maps a split may use."""
        return self.hdri_test if split == "test" else self.hdri_train

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        return {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}

    def replace(self, **changes) -> SynthConfig:
        return dataclasses.replace(self, **changes)

    @classmethod
    def from_dict(cls, d: dict) -> SynthConfig:
        if not isinstance(d, dict):
            raise InputError(f"config: expected a mapping of config keys, got {type(d).__name__}")
        return from_mapping(cls, d, "config")


def load_config(path) -> SynthConfig:
    """Read a :class:`SynthConfig` from a ``.json`` or ``.yaml``/``.yml`` file."""
    from ..io.documents import read_document

    path = Path(path)
    d = read_document(path, "config file", yaml_ok=path.suffix.lower() in (".yaml", ".yml"))
    if not isinstance(d, dict):
        raise InputError(f"{path}: expected a mapping of config keys")
    return SynthConfig.from_dict(d)


def sample_seed(cfg: SynthConfig, split: str, index: int) -> np.random.SeedSequence:
    """The seed sequence of sample ``index`` of ``split``: independent of who makes it.

    Raises:
        InputError: ``cfg`` not a :class:`SynthConfig`, an unknown split, ``index`` not an integer >= 0.
    """
    if not isinstance(cfg, SynthConfig):
        raise InputError(f"cfg: expected a SynthConfig, got {type(cfg).__name__}")
    if split not in SPLITS:
        raise InputError(f"split: expected one of {SPLITS}, got {short(split)}")
    if isinstance(index, bool) or not isinstance(index, int | np.integer):
        raise InputError(f"index: expected an integer, got {short(index)}")
    if index < 0:
        raise InputError(f"index: expected >= 0, got {index}")
    return np.random.SeedSequence([cfg.seed, SPLITS.index(split), int(index)])
