"""The training configuration: :class:`TrainConfig` and its typed sections, read from YAML.

A run's YAML file (``train/configs/*.yaml``) is a mapping of the fields of :class:`TrainConfig`;
its sections are mappings of the fields of their own dataclasses: ``net`` of
:class:`~relightnet.model.network.NetConfig`, ``loss`` of :class:`~relightnet.model.losses.LossWeights`,
``augment`` of :class:`AugmentConfig` and ``photo`` of
:class:`~relightnet.model.photo_input.PhotoInput`. Given as mappings (YAML, or keyword arguments), the
sections become those dataclasses; string modes are ``Literal`` types checked against their choices
(:func:`relightnet.checks.check_choices`). A checkpoint stores :meth:`TrainConfig.to_dict` (plain
values); :meth:`TrainConfig.from_dict` reads it back, older checkpoints' partial sections included.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from ..checks import InputError, check_choices
from ..io.documents import clip, from_mapping, short
from .losses import LossWeights
from .network import NetConfig
from .photo_input import PhotoInput, photo_input

__all__ = ["TrainConfig", "AugmentConfig", "load_train_config", "Target", "RenderTarget", "Precision", "DataDtype",
           "NovelLight"]

#: The transport field a run learns.
Target = Literal["transport", "transport_unoccluded"]
#: What the rendering losses compare with.
RenderTarget = Literal["image", "model"]
#: The network's arithmetic in training.
Precision = Literal["fp32", "bf16"]
#: How the training split is held in memory.
DataDtype = Literal["float32", "float16"]
#: How the lights of the novel-light loss terms are drawn (:data:`~relightnet.model.round_trip.NOVEL_LIGHTS`).
NovelLight = Literal["batch", "side"]


@dataclass(frozen=True)
class AugmentConfig:
    """The ``augment`` section: the arguments of :class:`relightnet.data.Augment` (its defaults).

    ``crop_scale`` and ``intensity`` are (lo, hi) pairs or None; ``mode`` the resampling of ``size``.
    """

    flip: float = 0.5
    crop_scale: tuple[float, float] | None = (0.75, 1.0)
    size: int | None = None
    multiple: int = 16
    intensity: tuple[float, float] | None = (0.5, 2.0)
    white_balance: float = 0.1
    mode: Literal["nearest", "bilinear"] = "nearest"

    def __post_init__(self) -> None:
        for name in ("crop_scale", "intensity"):
            v = getattr(self, name)
            if v is None:
                continue
            if not (isinstance(v, (list, tuple)) and len(v) == 2
                    and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)):
                raise InputError(f"train config augment.{name}: expected [lo, hi], got {short(v)}")
            object.__setattr__(self, name, tuple(v))
        check_choices(self, "train config augment")


def _section(cls, value, name: str):
    """A section given as a mapping (or already typed) as ``cls``."""
    return from_mapping(cls, value, f"train config {name}")


def _plain(value):
    """Tuples as lists, all the way down (what YAML gives)."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _default_augment() -> AugmentConfig:
    return AugmentConfig(crop_scale=(0.875, 0.875))


@dataclass(frozen=True)
class TrainConfig:
    """A training run. ``target`` selects the transport field: ``transport`` (occlusion-aware)
    or ``transport_unoccluded`` (the ablation "occlusion ignored"); ``render_target`` is what the
    rendering losses compare Â ⊙ (T̂·L̂) etc. with: ``image`` (the input photo, KE18) or ``model``
    (A ⊙ (T·L) with the target transport, so that the rendering terms agree with the transport the
    network learns — for ``transport_unoccluded`` the photo's occlusion shading would otherwise leak
    into the albedo); ``init`` starts from the weights of a checkpoint (fine-tuning) instead of a
    random initialisation; ``precision`` ``fp32`` or ``bf16`` (autocast of the network's
    convolutions; losses and the light solve stay float32) and ``channels_last`` (NHWC
    memory format) are speed settings (BENCHMARKS.md measures them); ``data_dtype`` ``float16``
    halves the memory of the training split held in RAM (10,000 people at 128²: 5 GB instead of
    10 GB; images and maps keep 11 bits of mantissa); ``train_items`` trains on the first N items of
    the split only (a smaller run on the same dataset); ``novel_light`` draws the lights of the
    ``relit_novel`` and ``round_trip`` loss terms (:func:`~relightnet.model.round_trip.novel_lights`).

    The sections: ``net`` the architecture (its ``lmax`` and ``input_size`` are set from the data),
    ``loss`` the loss weights, ``augment`` the augmentation (an empty mapping or None: none) and
    ``photo`` the photo framing (an empty mapping or None: the renders as they are); each may be
    given as a mapping of its fields.

    Example:
        >>> from relightnet.model.train_config import TrainConfig
        >>> cfg = TrainConfig(steps=10, net={"width": 8, "light_mode": "solve"}, loss={"tv": 0.1})
        >>> cfg.net.light_mode, cfg.net.width, cfg.loss.tv, cfg.augment.crop_scale
        ('solve', 8, 0.1, (0.875, 0.875))
        >>> TrainConfig.from_dict(cfg.to_dict()) == cfg
        True
        >>> TrainConfig(precision="fp8")
        Traceback (most recent call last):
            ...
        relightnet.errors.InputError: train config precision: expected one of 'fp32', 'bf16', got 'fp8'
    """

    steps: int = 1000
    batch_size: int = 8
    lr: float = 2e-3
    weight_decay: float = 1e-4
    warmup: int = 50
    seed: int = 0
    checkpoint_every: int = 100
    log_every: int = 10
    target: Target = "transport"
    render_target: RenderTarget = "image"
    net: NetConfig = field(default_factory=NetConfig)
    loss: LossWeights = field(default_factory=LossWeights)
    augment: AugmentConfig | None = field(default_factory=_default_augment)
    threads: int = 0
    init: str | None = None
    precision: Precision = "fp32"
    channels_last: bool = False
    data_dtype: DataDtype = "float32"
    train_items: int | None = None
    photo: PhotoInput | None = None
    novel_light: NovelLight = "batch"

    def __post_init__(self) -> None:
        for name in ("steps", "batch_size", "checkpoint_every", "log_every"):
            if not isinstance(getattr(self, name), int) or getattr(self, name) < 1:
                raise InputError(f"train config {name}: expected an integer >= 1, got {short(getattr(self, name))}")
        if not self.lr > 0:
            raise InputError(f"train config lr: expected > 0, got {short(self.lr)}")
        check_choices(self, "train config")
        if self.train_items is not None and (not isinstance(self.train_items, int) or isinstance(self.train_items, bool)
                                             or self.train_items < 1):
            raise InputError(f"train config train_items: expected an integer >= 1, got {short(self.train_items)}")
        object.__setattr__(self, "net", _section(NetConfig, self.net, "net"))
        object.__setattr__(self, "loss", _section(LossWeights, self.loss, "loss"))
        aug = None if not self.augment else _section(AugmentConfig, self.augment, "augment")
        object.__setattr__(self, "augment", aug)
        if not isinstance(self.photo, PhotoInput):
            object.__setattr__(self, "photo", photo_input({} if self.photo is None else self.photo))
        if aug is not None and aug.crop_scale is not None and aug.crop_scale[0] != aug.crop_scale[1] \
                and aug.size is None:
            raise InputError(
                f"train config augment.crop_scale: a range {list(aug.crop_scale)} gives items of different sizes; "
                "use a fixed scale [s, s] or set augment.size so that batches stack"
            )

    def to_dict(self) -> dict:
        """Plain values (sections as mappings, pairs as lists), what a checkpoint stores."""
        return _plain(dataclasses.asdict(self))

    @classmethod
    def from_dict(cls, d: dict, where: str = "training config") -> TrainConfig:
        """The config of a mapping (:meth:`to_dict`, a YAML file or an older checkpoint's, whose missing
        keys take their defaults); unknown keys are an error.

        Raises:
            InputError: one line starting with ``where``.
        """
        unknown = set(d) - {f.name for f in dataclasses.fields(cls)}
        if unknown:
            raise InputError(f"{where}: unknown keys {short(sorted(map(str, unknown)))}")
        try:
            return cls(**d)
        except InputError:
            raise
        except (TypeError, ValueError, OverflowError, AttributeError) as e:  # a value of the wrong type
            raise InputError(f"{where}: a setting has the wrong type ({clip(str(e), 160)})") from None


def load_train_config(path) -> TrainConfig:
    """Read a :class:`TrainConfig` from YAML/JSON; unknown keys are an error."""
    from ..io.documents import read_document

    path = Path(path)
    d = read_document(path, "training config")
    d = {} if d is None else d
    if not isinstance(d, dict):
        raise InputError(f"{path}: expected a mapping of training settings, got {type(d).__name__}")
    return TrainConfig.from_dict(d, str(path))
