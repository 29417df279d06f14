"""Contact sheet of a dataset: one row per sample, one column per map, as one PNG.

Columns (each ``res`` × ``res``; maps the dataset lacks are skipped):

1. ``image`` — the render, auto-exposed, sRGB
2. ``composite`` — ``image_composite`` (person over background), as stored
3. ``albedo`` — sRGB
4. ``shading`` — T · L, auto-exposed, sRGB
5. ``mask``
6. ``normals`` — light frame, (n + 1)/2 as RGB
7. ``T dc`` — transport band 0, grey, scaled by its unshadowed maximum π·Y₀
8. ``T l=1`` — transport (x, y, z) = (k 3, 1, 2) as RGB, 0.5 + 0.5·T / max
9. ``T l=2`` — transport (xy, yz, xz) = (k 4, 5, 7) as RGB, same mapping
10. ``occlusion`` — T₀ / T₀ unoccluded (ambient occlusion), grey

Clips contribute their first frame. The log names, row by row, the garment and hair meshes
each person wears (``meta["garments"]["types"]``; "painted" when none).
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError
from ..color import linear_to_srgb
from ..io import write_image
from .config import SPLITS
from .shards import dataset_config, load_manifest, read_shard

__all__ = ["preview", "preview_columns", "contact_sheet"]

logger = logging.getLogger("relightnet.data.preview")

_FIELDS = ("image", "image_composite", "albedo", "transport", "transport_unoccluded", "light", "mask", "normals")


def _exposed(img: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    from ..light.visualize import auto_exposure

    return linear_to_srgb((img * auto_exposure(img, mask > 0.5)).clamp(0, 1))


def _signed(t: torch.Tensor, scale: float) -> torch.Tensor:
    return (0.5 + 0.5 * t / scale).clamp(0, 1)


def preview_columns(s: dict) -> list[tuple[str, torch.Tensor]]:
    """Display tiles of one sample: [(column name, (H, W, 3) float in [0, 1], already encoded)].

    Args:
        s: one sample's stored arrays (channels-last numpy or tensors): ``image``, ``albedo``,
            ``transport`` (H, W, K), ``light`` (K, 3), ``mask``, ... (missing ones are skipped).
    """
    a = {k: torch.as_tensor(np.asarray(v)) for k, v in s.items() if k in _FIELDS}
    ref = next(v for k, v in a.items() if k != "light")
    h, w = ref.shape[:2]
    mask = a["mask"].float() if "mask" in a else torch.ones(h, w)
    cols: list[tuple[str, torch.Tensor]] = []
    if "image" in a:
        cols.append(("image", _exposed(a["image"].float(), mask)))
    if "image_composite" in a:
        cols.append(("composite", a["image_composite"].float() / 255.0))
    if "albedo" in a:
        cols.append(("albedo", linear_to_srgb(a["albedo"].float().clamp(0, 1))))
    T = a.get("transport")
    if T is not None and "light" in a:
        cols.append(("shading", _exposed(T.float() @ a["light"].float(), mask)))
    cols.append(("mask", mask[..., None].expand(h, w, 3)))
    if "normals" in a:
        cols.append(("normals", (a["normals"].float() * 0.5 + 0.5).clamp(0, 1) * mask[..., None]))
    if T is not None:
        T = T.float()
        cols.append(("T dc", (T[..., :1] / (math.pi * 0.282095)).clamp(0, 1).expand(h, w, 3)))
        if T.shape[-1] >= 4:
            cols.append(("T l=1", _signed(T[..., [3, 1, 2]], 2 * math.pi / 3 * 0.488603) * mask[..., None]))
        if T.shape[-1] >= 9:
            cols.append(("T l=2", _signed(T[..., [4, 5, 7]], math.pi / 4 * 1.092548 / 2) * mask[..., None]))
        if "transport_unoccluded" in a:
            ao = T[..., 0] / a["transport_unoccluded"].float()[..., 0].clamp_min(1e-6)
            cols.append(("occlusion", (ao.clamp(0, 1) * mask)[..., None].expand(h, w, 3)))
    return cols


def contact_sheet(samples: list[dict]) -> tuple[torch.Tensor, list[str]]:
    """Tile samples into one (n·H, C·W, 3) float image in [0, 1] (display-encoded) and the column names."""
    if not samples:
        raise InputError("contact_sheet: no samples")
    rows, names = [], None
    for s in samples:
        cols = preview_columns(s)
        if names is None:
            names = [n for n, _ in cols]
        rows.append(torch.cat([t for _, t in cols], dim=1))
    return torch.cat(rows, dim=0), names


def preview(root, out_png=None, n: int = 8, split: str | None = None) -> Path:
    """Write a contact sheet of the first ``n`` samples of a dataset folder.

    Args:
        root: dataset folder. out_png: output PNG (default ``root/preview.png``).
        n: samples (rows). split: which split (default: the first one with shards).

    Returns:
        The PNG path; the sheet is ``n·res`` high and ``columns·res`` wide
        (see the module docstring for the columns).
    """
    root = Path(root)
    manifest = load_manifest(root)
    cfg = dataset_config(manifest)
    if int(n) != n or n < 1:
        raise InputError(f"n: expected a positive integer, got {n!r}")
    out_png = Path(out_png) if out_png is not None else root / "preview.png"
    if out_png.suffix.lower() != ".png":
        raise InputError(f"{out_png}: expected a .png output file")
    splits = [split] if split is not None else [s for s in SPLITS if manifest["splits"].get(s, {}).get("shards")]
    if not splits or split is not None and not manifest["splits"].get(split, {}).get("shards"):
        raise InputError(f"{root}: no finished shards{'' if split is None else f' in split {split!r}'} to preview")
    samples: list[dict] = []
    worn: list[str] = []
    for e in manifest["splits"][splits[0]]["shards"]:
        fields = [f for f in _FIELDS if f in manifest.get("fields", {})]
        arrays = read_shard(root / e["file"], [*fields, "meta"])
        metas = arrays.pop("meta")
        for j in range(len(next(iter(arrays.values())))):
            s = {k: v[j] for k, v in arrays.items()}
            m = metas[j] if j < len(metas) and isinstance(metas[j], dict) else {}
            worn.append(", ".join(m.get("garments", {}).get("types", [])) or "painted")
            if cfg.sequence_frames:
                s = {k: v[0] for k, v in s.items()}
            samples.append(s)
            if len(samples) == n:
                break
        if len(samples) == n:
            break
    sheet, names = contact_sheet(samples)
    write_image(out_png, sheet, srgb=False)
    logger.info("wrote %s: %d samples of %s; columns: %s", out_png, len(samples), splits[0], ", ".join(names))
    for i, w in enumerate(worn[:len(samples)]):
        logger.info("row %d wears: %s", i, w)
    return out_png
