"""Real-pixel scenes with an exact person mask: generated people over real photographs.

The people are Anny bodies with painted clothes rendered by the package's own generator
(``relightnet.data.generate_sample`` / ``generate_sequence``); the backgrounds are real
photographs bundled with scikit-image. Used by the segmentation tests and by
``benchmarks/bench_segment.py``.
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F

#: scikit-image's photographs of real scenes without a person (brick: grey; not "camera": it shows one).
BACKGROUNDS = ("coffee", "rocket", "chelsea", "motorcycle", "brick")


def background(name: str, size: tuple[int, int]) -> torch.Tensor:
    """A real photograph cropped to the aspect of ``size`` (H, W) and resized: (3, H, W) sRGB in [0, 1]."""
    from skimage import data

    img = data.stereo_motorcycle()[0] if name == "motorcycle" else getattr(data, name)()
    if img.ndim == 2:
        img = np.repeat(img[..., None], 3, axis=-1)
    x = torch.from_numpy(np.ascontiguousarray(img[..., :3])).permute(2, 0, 1).float() / 255
    h, w = x.shape[1:]
    aspect = size[1] / size[0]
    if w / h > aspect:
        cw = int(round(h * aspect))
        x = x[:, :, (w - cw) // 2:(w - cw) // 2 + cw]
    else:
        ch = int(round(w / aspect))
        x = x[:, (h - ch) // 2:(h - ch) // 2 + ch]
    return F.interpolate(x[None], size=size, mode="bilinear", align_corners=False, antialias=True)[0].clamp(0, 1)


def person_cutout(arrays: dict, exposure: float = 0.25, crop: tuple[slice, slice] | None = None,
                  ) -> tuple[torch.Tensor, torch.Tensor]:
    """A generated person as (3, h, w) sRGB and (h, w) coverage, cut to the mask's box (or to ``crop``,
    (rows, columns), e.g. one box for every frame of a clip).

    The linear render is scaled so that the person's median luminance is ``exposure``.
    """
    from relightnet.color import linear_to_srgb

    img = torch.as_tensor(np.asarray(arrays["image"])).float()
    mask = torch.as_tensor(np.asarray(arrays["mask"])).float()
    if crop is None:
        ys, xs = torch.nonzero(mask > 0.5, as_tuple=True)
        crop = (slice(int(ys.min()), int(ys.max()) + 1), slice(int(xs.min()), int(xs.max()) + 1))
    lum = img[mask > 0.5].mean(-1).median().clamp_min(1e-4)
    rgb = linear_to_srgb((img * (exposure / lum)).clamp(0, 1))
    return rgb[crop].permute(2, 0, 1), mask[crop]


def place(bg: torch.Tensor, person: torch.Tensor, cover: torch.Tensor, height: float, cx: float,
          bottom: float) -> tuple[torch.Tensor, torch.Tensor]:
    """Composite a cut-out person over a (3, H, W) background.

    Args:
        height: the person's height as a fraction of the frame height.
        cx, bottom: the person's horizontal centre and feet as fractions of the frame's width and height.

    Returns:
        (image (3, H, W), true mask (H, W) in {0, 1}: coverage above one half).
    """
    from relightnet.render import composite

    H, W = bg.shape[1:]
    ph = max(int(round(height * H)), 2)
    pw = max(int(round(person.shape[2] * ph / person.shape[1])), 1)
    p = F.interpolate(person[None], size=(ph, pw), mode="bilinear", align_corners=False, antialias=True)[0]
    a = F.interpolate(cover[None, None], size=(ph, pw), mode="bilinear", align_corners=False, antialias=True)[0, 0]
    x0, y0 = int(round(cx * W - pw / 2)), int(round(bottom * H)) - ph
    alpha = torch.zeros(H, W)
    fg = torch.zeros(3, H, W)
    ix0, iy0, ix1, iy1 = max(x0, 0), max(y0, 0), min(x0 + pw, W), min(y0 + ph, H)
    alpha[iy0:iy1, ix0:ix1] = a[iy0 - y0:iy1 - y0, ix0 - x0:ix1 - x0]
    fg[:, iy0:iy1, ix0:ix1] = p[:, iy0 - y0:iy1 - y0, ix0 - x0:ix1 - x0]
    out = composite(fg.permute(1, 2, 0)[None], alpha.clamp(0, 1)[None], bg.permute(1, 2, 0))[0]
    return out.permute(2, 0, 1), (alpha > 0.5).float()


def iou(a: torch.Tensor, b: torch.Tensor) -> float:
    """Intersection over union of two (H, W) masks (above 0.5)."""
    a, b = a > 0.5, b > 0.5
    return float((a & b).sum()) / max(float((a | b).sum()), 1.0)


def flip_rate(masks: list[torch.Tensor]) -> float:
    """Mean fraction of a frame's pixels whose mask value changes from one frame to the next."""
    pairs = zip(masks[:-1], masks[1:], strict=True)
    return float(np.mean([float(((a > 0.5) ^ (b > 0.5)).float().mean()) for a, b in pairs]))
