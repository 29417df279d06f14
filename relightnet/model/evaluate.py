"""Evaluation of the CNN on a held-out split (unseen bodies and unseen HDRIs) against baselines.

Relighting is measured under a *novel* light: test item i is relit with the ground-truth
light of item (i + 1) mod n, so a prediction cannot score by echoing its own input.
``relit_*`` relight the CNN's albedo (KE18); ``relit_rmse_photo_albedo`` relights the photo
divided by the predicted shading (:func:`~relightnet.model.photo_albedo`), as
``relight-image`` does by default.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError
from ..color import linear_to_srgb
from ..io import atomic_write, write_image
from .maps import shade_map, shading_map
from .network import Prediction, RelightNet
from .photo_albedo import photo_albedo
from .training import batch_to_input

__all__ = ["evaluate", "baseline_from_train", "format_table", "format_ablation", "write_report"]


def _rmse(a: torch.Tensor, b: torch.Tensor, mask: torch.Tensor) -> float:
    """Root mean squared error over masked pixels and channels of (B, C, H, W) tensors."""
    n = (mask.sum() * a.shape[1]).clamp_min(1)
    return float((((a - b) ** 2) * mask).sum() / n) ** 0.5


def _psnr_ssim(pred: torch.Tensor, gt: torch.Tensor, mask: torch.Tensor) -> tuple[float, float]:
    """PSNR (over masked pixels only) and SSIM (scikit-image, background zeroed in both) of
    (3, H, W) linear images, in display (sRGB) space."""
    from skimage.metrics import structural_similarity

    p = (linear_to_srgb(pred.clamp(0, 1)) * mask).permute(1, 2, 0).numpy().astype(np.float64)
    g = (linear_to_srgb(gt.clamp(0, 1)) * mask).permute(1, 2, 0).numpy().astype(np.float64)
    mse = float(((p - g) ** 2).sum() / max(float(mask.sum()) * 3, 1))
    psnr = 10 * math.log10(1 / mse) if mse > 0 else float("inf")
    ssim = structural_similarity(p, g, channel_axis=2, data_range=1.0)
    return psnr, float(ssim)


def baseline_from_train(data_dir, target: str = "transport") -> dict:
    """Trivial predictors from the training split: mean albedo, mean transport (over the people's
    pixels), mean light. Streams the split item by item (memory does not grow with the split).

    Returns:
        ``albedo`` (3,), ``transport`` (K,), ``light`` (K, 3).
    """
    from ..data.dataset import SynthDataset

    ds = SynthDataset(data_dir, "train", fields=("mask", "albedo", "light", target), cache_shards=1)
    if len(ds) == 0:
        raise InputError(f"{data_dir}: the train split is empty")
    sums: dict = {}
    for i in range(len(ds)):
        item = ds[i]
        m = item["mask"].double()
        parts = {"albedo": (item["albedo"].double() * m).sum((1, 2)), "light": item["light"].double(),
                 "transport": (item[target].double() * m).sum((1, 2)), "pixels": m.sum()}
        for k, v in parts.items():
            sums[k] = sums[k] + v if k in sums else v
    n = sums["pixels"].clamp_min(1)
    return {"albedo": (sums["albedo"] / n).float(), "transport": (sums["transport"] / n).float(),
            "light": (sums["light"] / len(ds)).float()}


@torch.no_grad()
def _score(add, A: torch.Tensor, T: torch.Tensor, L: torch.Tensor, novel: torch.Tensor, truth: dict):
    """Score one candidate's maps (A (B, 3, H, W), T (B, K, H, W), L (B, K, 3)) item by item against the
    truth, relit under the ``novel`` lights: ``add(metric, value)`` per item; returns (relit, shading)."""
    M, T_gt = truth["mask"], truth["transport"]
    S_new, S_pred = shading_map(T, novel), shading_map(T, L)
    relit = A * S_new
    # As relight-image does by default: the photo (clipped as a camera would) divided by the
    # predicted shading is relit.
    relit_photo = photo_albedo(truth["image"].clamp(0, 1), Prediction(A, T, L, M), shading=S_pred) * S_new
    gt_relit, concave = truth["relit"], truth["concave"]
    for j in range(A.shape[0]):
        sl = slice(j, j + 1)
        add("transport_rmse", _rmse(T[sl], T_gt[sl], M[sl]))
        add("albedo_rmse", _rmse(A[sl], truth["albedo"][sl], M[sl]))
        add("light_rmse", float(((L[sl] - truth["light"][sl]) ** 2).mean()) ** 0.5)
        add("shading_rmse", _rmse(S_pred[sl], truth["shading"][sl], M[sl]))
        add("relit_rmse", _rmse(relit[sl], gt_relit[sl], M[sl]))
        add("relit_rmse_photo_albedo", _rmse(relit_photo[sl], gt_relit[sl], M[sl]))
        if concave[sl].sum() > 0:
            add("relit_rmse_concave", _rmse(relit[sl], gt_relit[sl], concave[sl]))
        psnr, ssim = _psnr_ssim(relit[j].cpu(), gt_relit[j].cpu(), M[j].cpu())
        add("relit_psnr", psnr)
        add("relit_ssim", ssim)
    return relit, S_pred


def _items(data_dir, split: str, photo: bool) -> tuple[list, tuple]:
    """A split's items in memory (framed as photos when ``photo``) and the fields a batch stacks."""
    from ..data.dataset import SynthDataset
    from .photo_input import as_photo

    fields = ("image", "mask", "albedo", "light", "transport", "transport_unoccluded")
    ds = SynthDataset(data_dir, split, fields=(*fields, "image_composite") if photo else fields, cache_shards=1)
    if len(ds) < 2:
        raise InputError(f"{data_dir}: the {split} split needs at least 2 items to evaluate relighting")
    items = [ds[i] for i in range(len(ds))]
    if not photo:
        return items, fields
    return [as_photo({k: v.float() for k, v in it.items()}, True, 1.0, 0, 0.05) for it in items], (*fields, "input")


def evaluate(model: RelightNet, data_dir, split: str = "test", target: str = "transport", batch: int = 4,
             baseline: dict | None = None, sheet: str | Path | None = None, concave_threshold: float = 0.1,
             twin: RelightNet | None = None, floor: bool = False, photo: bool = False) -> dict:
    """Masked RMSEs, PSNR and SSIM of the model (and of the baseline, when given) on a split.

    Args:
        model: network in eval mode.
        data_dir: dataset folder.
        split: split to evaluate (``test``: unseen bodies and HDRIs).
        target: ground-truth transport field.
        baseline: output of :func:`baseline_from_train` to score alongside.
        sheet: write a contact sheet PNG (input | albedo | shading | relit, prediction over truth).
        concave_threshold: "concave" pixels are those where occluded and unoccluded DC transport
            differ by more than this fraction; relit RMSE is also reported there.
        twin: KE18's occlusion ablation: a second network (trained on ``transport_unoccluded``)
            scored on the same items, as ``"ablation"``.
        floor: also score what ignoring occlusion costs at best — the true albedo with the true
            *unoccluded* transport — as ``"occlusion_floor"``.
        photo: score the items as photos: each item's composite (over its background) framed
            around its mask as ``relight-image`` frames a photo, the truth resampled onto the same
            box (:func:`~relightnet.model.photo_input.as_photo`); else the renders at their own framing.

    Returns:
        ``{"model": {metric: value}, "baseline": {...}, "ablation": {...}, "occlusion_floor": {...}}``
        (the last three when asked for).
    """
    items, fields = _items(data_dir, split, photo)
    n = len(items)
    dev = next(model.parameters()).device
    sums: dict = {"model": {}, "baseline": {}, "ablation": {}, "occlusion_floor": {}}
    rows = []

    def add(who, key, value):
        sums[who].setdefault(key, []).append(value)

    for s in range(0, n, batch):
        chunk = items[s : s + batch]
        b = {k: torch.stack([it[k] for it in chunk]).to(dev) for k in fields}
        novel = torch.stack([items[(s + j + 1) % n]["light"] for j in range(len(chunk))]).to(dev)
        M = b["mask"]
        T_gt = b[target]
        dc = b["transport"][:, :1], b["transport_unoccluded"][:, :1]
        concave = M * ((dc[0] - dc[1]).abs() > concave_threshold * dc[1].abs().clamp_min(1e-6)).float()
        gt_s = shading_map(T_gt, b["light"])
        gt_relit = shade_map(b["albedo"], T_gt, novel)
        pred = model(batch_to_input(b))
        cands = {"model": (pred.albedo, pred.transport, pred.light)}
        if baseline is not None:
            B, _, H, W = M.shape
            cands["baseline"] = (baseline["albedo"].to(dev).view(1, 3, 1, 1).expand(B, 3, H, W),
                                 baseline["transport"].to(dev).view(1, -1, 1, 1).expand(B, -1, H, W),
                                 baseline["light"].to(dev).expand(B, -1, 3))
        if twin is not None:
            p = twin(batch_to_input(b))
            cands["ablation"] = (p.albedo, p.transport, p.light)
        if floor:
            cands["occlusion_floor"] = (b["albedo"], b["transport_unoccluded"], b["light"])
        truth = {"albedo": b["albedo"], "transport": T_gt, "light": b["light"], "shading": gt_s, "relit": gt_relit,
                 "image": b["image"], "mask": M, "concave": concave}
        for who, (A, T, L) in cands.items():
            relit, S_pred = _score(lambda k, v, who=who: add(who, k, v), A, T, L, novel, truth)
            if who == "model" and sheet is not None and len(rows) < 6:
                for j in range(min(len(chunk), 6 - len(rows))):
                    mj = M[j]
                    rows.append([b["image"][j], A[j] * mj, b["albedo"][j], S_pred[j] * mj, gt_s[j],
                                 relit[j] * mj, gt_relit[j]])
    result = {who: {k: float(np.mean(v)) for k, v in d.items()} for who, d in sums.items() if d}
    result["n"] = n
    result["as_photo"] = bool(photo)
    if sheet is not None and rows:
        _contact_sheet(rows, sheet)
    return result


def format_ablation(aware: dict, ignored: dict, floor: dict) -> str:
    """Markdown table of KE18's occlusion ablation: relit RMSE overall and on concave pixels of the
    occlusion-aware model, its occlusion-ignoring twin, and the floor (``evaluate(..., floor=True)``)."""
    lines = ["| model | relit RMSE | relit RMSE, concave pixels |", "|---|---|---|"]
    for name, r in (("occlusion-aware", aware), ("occlusion ignored (twin)", ignored),
                    ("true albedo + true unoccluded transport", floor)):
        lines.append(f"| {name} | {r['relit_rmse']:.4f} | {r['relit_rmse_concave']:.4f} |")
    gain = [1 - aware[k] / ignored[k] for k in ("relit_rmse", "relit_rmse_concave")]
    lines.append(f"| occlusion-aware lower by | {100 * gain[0]:.1f}% | {100 * gain[1]:.1f}% |")
    return "\n".join(lines)


def _contact_sheet(rows: list, path) -> None:
    """Rows: input | albedo pred | albedo truth | shading pred | shading truth | relit pred | relit truth."""
    tiles = []
    for r in rows:
        s = max(float(r[4].amax()), 1e-6)
        e = max(float(r[6].amax()), 1e-6)
        cols = [r[0], r[1], r[2], r[3] / s, r[4] / s, r[5] / e, r[6] / e]
        tiles.append(torch.cat([c.clamp(0, 1).cpu().permute(1, 2, 0) for c in cols], 1))
    write_image(path, torch.cat(tiles, 0))


def format_table(result: dict) -> str:
    """Markdown table of :func:`evaluate`'s result (model vs baseline, lower RMSE is better)."""
    keys = ["transport_rmse", "albedo_rmse", "light_rmse", "shading_rmse", "relit_rmse", "relit_rmse_concave",
            "relit_psnr", "relit_ssim", "relit_rmse_photo_albedo"]
    who = [w for w in ("model", "baseline") if w in result]
    lines = ["| metric | " + " | ".join(who) + " |", "|---|" + "---|" * len(who)]
    for k in keys:
        if all(k in result[w] for w in who):
            lines.append(f"| {k} | " + " | ".join(f"{result[w][k]:.4f}" for w in who) + " |")
    return "\n".join(lines)


def write_report(result: dict, path, extra: str = "") -> None:
    with atomic_write(path, "w") as f:
        how = " as photos (composites framed around their masks)" if result.get("as_photo") else ""
        f.write(f"Evaluated on {result['n']} items{how}.\n\n" + format_table(result) + extra + "\n")
