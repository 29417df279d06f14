"""The generator's result type and its per-body precomputation."""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field

import numpy as np
import torch

from ..body import AnnyBody
from ..body.albedo import region_labels
from ..checks import InputError
from ..light import preset_envmap
from .textures import UVAtlas, region_field, texel_regions, uv_atlas

__all__ = ["GENERATOR_VERSION", "TEXTURE_SIZE", "Sample", "SynthAssets", "prepare_assets", "assets_for"]

#: Bumped whenever the output of the generator changes for a given config.
GENERATOR_VERSION = "3"
#: Side of the UV albedo texture.
TEXTURE_SIZE = 512


@dataclass(frozen=True, eq=False)
class Sample:
    """One generated sample: ``arrays`` (see :mod:`relightnet.data.generate`; a leading T axis
    for clips) and JSON-serialisable ``meta``."""

    arrays: dict[str, np.ndarray]
    meta: dict


@dataclass
class SynthAssets:
    """What the generator precomputes once per body model (see :func:`prepare_assets`).

    Attributes:
        body: the :class:`~relightnet.body.AnnyBody`.
        atlas: its :class:`~relightnet.data.textures.UVAtlas`.
        regions: memo of region fields per (sleeves, legs, hair) variant, filled on use.
        texels: memo of their texel regions (:func:`~relightnet.data.textures.texel_regions`), filled on use.
        envmaps: memo of the shipped env maps, filled on use.
        tables: memo of the garment tables, filled on use.
    """

    body: AnnyBody
    atlas: UVAtlas
    regions: dict = field(default_factory=dict)
    texels: dict = field(default_factory=dict)
    envmaps: dict = field(default_factory=dict)
    tables: dict = field(default_factory=dict)

    def garment_tables(self):
        """The body's :class:`~relightnet.data.garments.GarmentTables` (built on first use)."""
        if "garments" not in self.tables:
            from .garments import garment_tables

            self.tables["garments"] = garment_tables(self.body, self.atlas.parts, self.tables.setdefault("labels", {}))
        return self.tables["garments"]

    def region_field(self, sleeves: str, legs: str, hair: str) -> np.ndarray:
        """(V, R) smoothed region field (:func:`~relightnet.data.textures.region_field`) of
        :func:`relightnet.body.albedo.region_labels` for one clothing variant."""
        key = (sleeves, legs, hair)
        if key not in self.regions:
            ids = self.region_labels(sleeves, legs, hair).numpy()
            self.regions[key] = region_field(self.body.faces.cpu().numpy(), ids)
        return self.regions[key]

    def texel_regions(self, sleeves: str, legs: str, hair: str) -> np.ndarray:
        """(S·S,) the region id of every texel for one clothing variant (the arg-max of its
        :meth:`region_field` at the texel, :func:`~relightnet.data.textures.texel_regions`)."""
        key = (sleeves, legs, hair)
        if key not in self.texels:
            self.texels[key] = texel_regions(self.atlas, self.region_field(sleeves, legs, hair))
        return self.texels[key]

    def region_labels(self, sleeves: str, legs: str, hair: str) -> torch.Tensor:
        """(V,) :func:`relightnet.body.albedo.region_labels` of one clothing variant (memo shared with the garments)."""
        labels = self.tables.setdefault("labels", {})
        key = (sleeves, legs, hair)
        if key not in labels:
            labels[key] = region_labels(self.body, sleeves, legs, hair, parts=self.atlas.parts)
        return labels[key]

    def envmap(self, name: str) -> torch.Tensor:
        """(He, We, 3) a shipped env map, clamped at 0."""
        if name not in self.envmaps:
            self.envmaps[name] = preset_envmap(name).clamp_min(0.0)
        return self.envmaps[name]


def prepare_assets(body: AnnyBody | None = None, texture_size: int = TEXTURE_SIZE) -> SynthAssets:
    """Build the per-body precomputation (the UV atlas, ~0.3 s; regions and env maps on first use).

    Args:
        body: an :class:`~relightnet.body.AnnyBody` (default: a new one).
        texture_size: side of the albedo texture.
    """
    body = AnnyBody() if body is None else body
    if not isinstance(body, AnnyBody):
        raise InputError(f"body: expected an AnnyBody, got {type(body).__name__}")
    return SynthAssets(body=body, atlas=uv_atlas(body, texture_size))


_ASSETS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def assets_for(body) -> SynthAssets:
    """The :class:`SynthAssets` to use for ``body`` (None, an AnnyBody, or SynthAssets).

    For an AnnyBody they are kept in a module-level ``weakref.WeakKeyDictionary`` keyed on
    the body object (they die with it); None builds a new body and assets every call.
    """
    if isinstance(body, SynthAssets):
        return body
    if body is None:
        return prepare_assets()
    if not isinstance(body, AnnyBody):
        raise InputError(f"body: expected None, an AnnyBody or SynthAssets, got {type(body).__name__}")
    if body not in _ASSETS:
        _ASSETS[body] = prepare_assets(body)
    return _ASSETS[body]
