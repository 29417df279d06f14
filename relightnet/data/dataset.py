"""``SynthDataset``: a torch Dataset over the shards of a synthetic dataset folder.

Items are dicts of tensors in the CNN layout (channels first):

================  ==================  ==========================================
field             shape               dtype / meaning
================  ==================  ==========================================
image             (3, H, W)           float32 linear RGB (the rendered person)
mask              (1, H, W)           float32 coverage in [0, 1]
albedo            (3, H, W)           float32 linear reflectance
transport         (K, H, W)           float32 SH transport (occlusion included)
light             (K, 3)              float32 SH light, linear RGB, light frame
normals           (3, H, W)           float32 light-frame normals
depth             (1, H, W)           float32
parts             (1, H, W)           uint8 part labels
image_srgb, ...   (3, H, W)           uint8 fields stay uint8
index             ()                  int64 item index
================  ==================  ==========================================

Clips (datasets made with ``--sequence T``) have a leading frame axis: image (T, 3, H, W),
light (T, K, 3). Shards are loaded lazily, only the requested fields, and kept in a small
per-process LRU cache (``cache_shards``), so memory stays bounded and the dataset works
with ``DataLoader(num_workers=...)`` (each worker has its own cache). For sequential or
shard-grouped access read shards in order; random access reloads shards often.
"""

from __future__ import annotations

import bisect
import collections
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError
from .augment import SPATIAL_FIELDS
from .config import SPLITS
from .shards import dataset_config, load_manifest, read_shard, read_shard_meta

__all__ = ["DEFAULT_FIELDS", "SynthDataset", "to_cnn_layout"]

#: Fields a SynthDataset returns by default.
DEFAULT_FIELDS = ("image", "mask", "albedo", "transport", "light", "normals")


def to_cnn_layout(name: str, arr: np.ndarray, sequence: bool = False) -> torch.Tensor:
    """One sample's field, channels-last as stored → a tensor in the CNN layout.

    Args:
        name: field name (spatial fields are listed in ``augment.SPATIAL_FIELDS``).
        arr: (H, W, C) or (H, W) — with a leading T when ``sequence`` — or any non-spatial array.

    Returns:
        (C, H, W) / (1, H, W) (or (T, C, H, W) / (T, 1, H, W)); other fields unchanged. Always a copy.
    """
    x = torch.from_numpy(np.array(arr, copy=True))
    if name not in SPATIAL_FIELDS:
        return x
    lead = 1 if sequence else 0
    if x.dim() == lead + 2:
        return x.unsqueeze(lead)
    if x.dim() == lead + 3:
        return x.movedim(-1, -3).contiguous()
    raise InputError(f"{name}: expected (H, W) or (H, W, C) per {'frame' if sequence else 'sample'}, "
                     f"got {tuple(arr.shape)}")


class SynthDataset(torch.utils.data.Dataset):
    """Samples of one split of a dataset folder made by ``relightnet synth``.

    Args:
        root: the dataset folder (with ``manifest.json``).
        split: ``"train"``, ``"val"`` or ``"test"``.
        fields: which fields to load and return (see the module docstring).
        augment: optional callable ``augment(sample, generator) -> sample``, e.g.
            :class:`relightnet.data.Augment`.
        augment_seed: None draws augmentations from torch's global RNG (DataLoader seeds
            it per worker and epoch); an int makes item i's augmentation fixed.
        cache_shards: shards kept in memory per process.
        allow_incomplete: use the finished shards of an unfinished dataset instead of failing.
    """

    def __init__(self, root, split: str = "train", fields=DEFAULT_FIELDS, augment=None,
                 augment_seed: int | None = None, cache_shards: int = 2, allow_incomplete: bool = False) -> None:
        self.root = Path(root)
        manifest = load_manifest(self.root)
        self.config = dataset_config(manifest)
        if split not in SPLITS:
            raise InputError(f"split: expected one of {SPLITS}, got {split!r}")
        info = manifest["splits"].get(split, {"shards": [], "n_shards": 0, "count": 0})
        if len(info["shards"]) != info["n_shards"] and not allow_incomplete:
            raise InputError(f"{self.root}: {split} has {len(info['shards'])} of {info['n_shards']} shards made; "
                             "finish it with 'relightnet synth' (or pass allow_incomplete=True)")
        self.fields = tuple(fields)
        known = set(manifest.get("fields", {}))
        missing = [f for f in self.fields if known and f not in known]
        if missing:
            raise InputError(f"fields: {missing} not in this dataset; it has {sorted(known)}")
        if cache_shards < 1:
            raise InputError(f"cache_shards: expected >= 1, got {cache_shards}")
        self.split, self.augment, self.augment_seed, self.cache_shards = split, augment, augment_seed, cache_shards
        self.sequence = bool(self.config.sequence_frames)
        self._files = [self.root / e["file"] for e in info["shards"]]
        self._starts = [0]
        for e in info["shards"]:
            self._starts.append(self._starts[-1] + int(e["count"]))
        self._cache: collections.OrderedDict = collections.OrderedDict()

    def __len__(self) -> int:
        return self._starts[-1]

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["_cache"] = collections.OrderedDict()  # each DataLoader worker loads its own shards
        return state

    def _locate(self, i: int) -> tuple[int, int]:
        n = len(self)
        if not -n <= i < n:
            raise IndexError(f"index {i} out of range for {n} items")
        i %= n
        s = bisect.bisect_right(self._starts, i) - 1
        return s, i - self._starts[s]

    def _shard(self, s: int) -> dict:
        if s in self._cache:
            self._cache.move_to_end(s)
            return self._cache[s]
        arrays = read_shard(self._files[s], self.fields)
        self._cache[s] = arrays
        while len(self._cache) > self.cache_shards:
            self._cache.popitem(last=False)
        return arrays

    def __getitem__(self, i: int) -> dict:
        i = int(i)
        s, off = self._locate(i)
        arrays = self._shard(s)
        sample = {name: to_cnn_layout(name, arrays[name][off], self.sequence) for name in self.fields}
        if self.augment is not None:
            g = None
            if self.augment_seed is not None:
                g = torch.Generator().manual_seed(int(np.random.SeedSequence([self.augment_seed, i % len(self)])
                                                     .generate_state(1)[0]))
            sample = self.augment(sample, g)
        sample["index"] = torch.tensor(i % len(self))
        return sample

    def meta(self, i: int) -> dict:
        """The generator's metadata of item ``i`` (seed, light source, camera, ...)."""
        s, off = self._locate(int(i))
        return read_shard_meta(self._files[s])[off]

    def __repr__(self) -> str:
        return f"SynthDataset({str(self.root)!r}, split={self.split!r}, n={len(self)}, fields={self.fields})"
