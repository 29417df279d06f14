"""Default albedo for Anny: per-vertex regions, colours, and a UV texture.

Anny ships no colour texture, only a body-part segmentation painted in UV space
(``anny/data/segmentation/body_parts_segmentation.{png,yaml}``, 1024², 14 parts:
``body, head, hand.L/R, foot.L/R, eye_front.L/R, eye_back.L/R, eye_cavity.L/R,
mouth_cavity, tongue``). Its parts map to relightnet's :data:`REGIONS` like this:

- ``hand.*`` → skin; ``foot.*`` → shoes;
- ``head``, eyes, cavities, tongue → skin, except the scalp → hair (a geometric
  hairline on the zero-pose mesh: above the brow in front, down to the nape behind);
- ``body`` (torso, arms, legs, neck) is split with the skinning weights (the bone of
  largest weight) and the zero-pose joints: torso bones above the waist (root joint
  + 5 cm) and below the neckline → top, below the waist → bottom; arm vertices → top
  up to a sleeve length measured from shoulder to wrist (``sleeves``), else skin; leg
  vertices → bottom down to a length from hip to ankle (``legs``), shoes above the
  ankle, skin between; neck → skin.

Colours are linear RGB in [0.02, 0.9]. Texture layout: (H, W, 3) channels-last, row 0
is the top of the image, i.e. texel (row, col) holds uv = ((col + ½)/W, 1 − (row + ½)/H)
(the usual image / OBJ convention, as Anny's segmentation PNG).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import torch

from ..checks import InputError
from ..color import srgb_to_linear_np

__all__ = [
    "REGIONS",
    "Albedo",
    "anny_part_labels",
    "ANNY_PARTS",
    "region_labels",
    "skin_color",
    "default_albedo",
    "vertex_to_texture",
]

#: Region names; ``region_labels`` returns indices into this tuple.
REGIONS = ("skin", "hair", "top", "bottom", "shoes")

#: Anny's segmentation part names, in the order of ``anny_part_labels`` ids.
ANNY_PARTS = (
    "body", "head", "hand.R", "hand.L", "eye_back.L", "eye_front.L", "eye_back.R", "eye_front.R",
    "eye_cavity.R", "eye_cavity.L", "mouth_cavity", "foot.L", "foot.R", "tongue",
)

_SLEEVES = {"none": -0.05, "short": 0.3, "elbow": 0.5, "long": 0.97}
_LEGS = {"shorts": 0.4, "knee": 0.55, "long": 0.93}
_SHOE_START = 0.955  # fraction of hip → ankle where the shoes begin

# Skin anchors from light to dark (sRGB 0–255), converted to linear.
_SKIN_SRGB = np.array([[246, 214, 190], [232, 184, 148], [198, 145, 105], [160, 105, 70],
                       [110, 70, 45], [70, 45, 30]], dtype=np.float64)

_DEFAULT_COLORS = {
    "hair": (0.045, 0.028, 0.018),
    "top": (0.12, 0.22, 0.48),
    "bottom": (0.06, 0.06, 0.09),
    "shoes": (0.035, 0.03, 0.03),
    "iris": (0.06, 0.035, 0.02),
    "sclera": (0.72, 0.7, 0.66),
    "mouth": (0.35, 0.08, 0.08),
}


def skin_color(tone: float) -> torch.Tensor:
    """(3,) linear-RGB skin albedo; ``tone`` in [0, 1] from very light (0) to very dark (1)."""
    if not 0.0 <= float(tone) <= 1.0:
        raise InputError(f"skin_tone: expected a value in [0, 1], got {tone}")
    lin = srgb_to_linear_np(_SKIN_SRGB / 255.0)
    x = float(tone) * (len(lin) - 1)
    i = min(int(x), len(lin) - 2)
    c = lin[i] * (1 - (x - i)) + lin[i + 1] * (x - i)
    return torch.as_tensor(np.clip(c, 0.02, 0.9), dtype=torch.float32)


@dataclass(frozen=True)
class Albedo:
    """Per-vertex albedo (V, 3) and the UV texture (H, W, 3) painted from it (or None)."""

    vertex: torch.Tensor
    texture: torch.Tensor | None


def anny_part_labels(body) -> torch.Tensor:
    """(V,) int64 ids into :data:`ANNY_PARTS` from Anny's UV-space segmentation.

    Each face takes the part painted at its UV centre (as Anny does); a vertex takes the
    part most of its faces have.
    """
    import PIL.Image
    import yaml
    from anny.paths import get_anny_root_dir

    root = get_anny_root_dir() / "data" / "segmentation"
    img = np.asarray(PIL.Image.open(root / "body_parts_segmentation.png").convert("RGB")).astype(np.int64)
    with open(root / "body_parts_segmentation.yaml") as f:
        colors = yaml.safe_load(f)["colors"]
    if tuple(colors) != ANNY_PARTS:
        raise InputError(f"anny segmentation parts changed: {list(colors)}")
    palette = np.array([colors[p] for p in ANNY_PARTS], dtype=np.int64)
    uv = body.uv.detach().cpu().double().numpy()
    faces = body.faces.cpu().numpy()
    centre = uv[body.uv_faces.cpu().numpy()].mean(axis=1)
    h, w = img.shape[:2]
    rows = np.clip(np.round((1 - centre[:, 1]) * h).astype(np.int64), 0, h - 1)
    cols = np.clip(np.round(centre[:, 0] * w).astype(np.int64), 0, w - 1)
    px = img[rows, cols]
    face_part = ((px[:, None, :] - palette[None]) ** 2).sum(-1).argmin(1)
    counts = np.zeros((body.num_verts, len(ANNY_PARTS)), dtype=np.int64)
    for k in range(3):
        np.add.at(counts, (faces[:, k], face_part), 1)
    return torch.as_tensor(counts.argmax(1), dtype=torch.int64)


def _project(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Fraction along segment a → b of the projection of points p (N, 3)."""
    d = b - a
    return (p - a) @ d / float(d @ d)


def region_labels(body, sleeves: str = "short", legs: str = "long", hair: str = "short", parts=None) -> torch.Tensor:
    """(V,) int64 region ids into :data:`REGIONS` for an :class:`~relightnet.body.AnnyBody`.

    Args:
        body: the Anny body model (its topology, skinning weights and default zero pose are used).
        sleeves: ``"none"``, ``"short"``, ``"elbow"`` or ``"long"``.
        legs: ``"shorts"``, ``"knee"`` or ``"long"``.
        hair: ``"short"`` (scalp) or ``"none"`` (bald).
        parts: (V,) ``anny_part_labels(body)`` when the caller keeps them (they read an image); None reads them.
    """
    if sleeves not in _SLEEVES or legs not in _LEGS or hair not in ("short", "none"):
        raise InputError(
            f"region_labels: sleeves in {list(_SLEEVES)}, legs in {list(_LEGS)}, hair in ['short', 'none'];"
            f" got {sleeves!r}, {legs!r}, {hair!r}"
        )
    with torch.no_grad():
        out = body()
    v = out.verts[0].detach().cpu().double().numpy()
    J = {n: j for n, j in zip(out.joint_names, out.joints[0].detach().cpu().double().numpy(), strict=True)}
    part = np.asarray(anny_part_labels(body) if parts is None else parts)
    pid = {p: i for i, p in enumerate(ANNY_PARTS)}
    w = body.anny.vertex_bone_weights.detach().cpu().numpy()
    bi = body.anny.vertex_bone_indices.detach().cpu().numpy()
    names = np.array(body.joint_names)
    dom = names[bi[np.arange(len(bi)), w.argmax(1)]]

    region = np.zeros(len(v), dtype=np.int64)  # skin
    is_body = part == pid["body"]
    is_torso = is_body & np.isin(dom, ["root", "spine05", "spine04", "spine03", "spine02", "spine01",
                                       "pelvis.L", "pelvis.R"])
    waist = J["root"][1] + 0.05
    neckline = J["neck01"][1] - 0.035
    region[is_torso & (v[:, 1] >= waist) & (v[:, 1] < neckline)] = REGIONS.index("top")
    region[is_torso & (v[:, 1] < waist)] = REGIONS.index("bottom")
    for s in ("L", "R"):
        arm = is_body & np.isin(dom, [f"{b}.{s}" for b in ("clavicle", "shoulder01", "upperarm01", "upperarm02",
                                                         "lowerarm01", "lowerarm02", "wrist")])
        t = _project(v, J[f"upperarm01.{s}"], J[f"wrist.{s}"])
        region[arm & (t < _SLEEVES[sleeves]) & (v[:, 1] < neckline)] = REGIONS.index("top")
        leg = is_body & np.isin(dom, [f"{b}.{s}" for b in ("upperleg01", "upperleg02", "lowerleg01", "lowerleg02",
                                                         "foot")])
        t = _project(v, J[f"upperleg01.{s}"], J[f"foot.{s}"])
        region[leg & (t < _LEGS[legs])] = REGIONS.index("bottom")
        region[leg & (t >= _SHOE_START)] = REGIONS.index("shoes")
    region[(part == pid["foot.L"]) | (part == pid["foot.R"])] = REGIONS.index("shoes")
    if hair == "short":
        eye = (J["eye.L"] + J["eye.R"]) / 2
        dy, dz = v[:, 1] - eye[1], v[:, 2] - eye[2]
        scalp = (dy > 0.065) | ((dy > 0.02) & (dz < -0.06)) | ((dy > -0.075) & (dz < -0.1))
        region[(part == pid["head"]) & scalp] = REGIONS.index("hair")
    return torch.as_tensor(region, dtype=torch.int64)


def default_albedo(
    body,
    skin_tone: float = 0.3,
    colors: Mapping[str, tuple[float, float, float]] | None = None,
    texture_size: int | None = 512,
    regions: torch.Tensor | None = None,
) -> Albedo:
    """A plain-coloured Anny: skin of the given tone, hair, a top, a bottom, shoes.

    Args:
        body: :class:`~relightnet.body.AnnyBody`.
        skin_tone: 0 (very light) … 1 (very dark), see :func:`skin_color`.
        colors: linear-RGB overrides for ``hair``, ``top``, ``bottom``, ``shoes``, ``iris``,
            ``sclera``, ``mouth``, ``skin``.
        texture_size: side of the square UV texture, or None for per-vertex albedo only.
        regions: (V,) region ids (default :func:`region_labels` with its defaults).

    Returns:
        :class:`Albedo` with ``vertex`` (V, 3) and ``texture`` (S, S, 3), float32, in [0.02, 0.9].
    """
    cols = dict(_DEFAULT_COLORS)
    cols["skin"] = tuple(skin_color(skin_tone).tolist())
    for k, c in (colors or {}).items():
        if k not in cols:
            raise InputError(f"colors: unknown key {k!r}; expected some of {sorted(cols)}")
        cols[k] = tuple(float(x) for x in c)
    regions = region_labels(body) if regions is None else torch.as_tensor(regions, dtype=torch.int64)
    if regions.shape != (body.num_verts,):
        raise InputError(f"regions: expected ({body.num_verts},), got {tuple(regions.shape)}")
    table = torch.tensor([cols[r] for r in REGIONS], dtype=torch.float32)
    alb = table[regions.cpu()]
    part = anny_part_labels(body)
    pid = {p: i for i, p in enumerate(ANNY_PARTS)}
    for p, key in (("eye_front.L", "iris"), ("eye_front.R", "iris"), ("eye_back.L", "sclera"),
                   ("eye_back.R", "sclera"), ("mouth_cavity", "mouth"), ("tongue", "mouth")):
        alb[part == pid[p]] = torch.tensor(cols[key], dtype=torch.float32)
    alb = alb.clamp(0.02, 0.9)
    tex = None if texture_size is None else vertex_to_texture(body, alb, texture_size)
    return Albedo(vertex=alb, texture=tex)


def vertex_to_texture(body, values: torch.Tensor, size: int = 512) -> torch.Tensor:
    """Paint per-vertex values into a UV texture: each texel takes the vertex of the nearest UV.

    Texels outside the UV islands take the nearest island's value, which pads the islands
    for bilinear or mip-mapped lookups.

    Args:
        body: a body model with ``uv``, ``uv_faces`` and ``faces``.
        values: (V, C) per-vertex values.
        size: texture side S.

    Returns:
        (S, S, C) texture, dtype of ``values``; row 0 is v = 1.
    """
    from scipy.spatial import cKDTree

    if int(size) < 1:
        raise InputError(f"texture size: expected >= 1, got {size}")
    uv = body.uv.detach().cpu().double().numpy()
    vt2v = np.full(len(uv), -1, dtype=np.int64)
    vt2v[body.uv_faces.cpu().numpy().reshape(-1)] = body.faces.cpu().numpy().reshape(-1)
    used = np.nonzero(vt2v >= 0)[0]
    c = (np.arange(size) + 0.5) / size
    uu, vv = np.meshgrid(c, 1.0 - c)  # row 0 is v = 1
    _, nn = cKDTree(uv[used]).query(np.stack([uu.ravel(), vv.ravel()], axis=1))
    vid = torch.as_tensor(vt2v[used[nn]], dtype=torch.int64)
    return values.detach().cpu()[vid].reshape(size, size, -1).contiguous()
