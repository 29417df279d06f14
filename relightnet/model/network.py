"""The inverse-rendering CNN of the 2D path (Kanamori & Endo 2018 style).

An encoder–decoder with skip connections reads a masked image of a person and predicts

- ``transport`` (B, K, H, W): per-pixel SH transport, occlusion included. ``transport_head`` chooses
  its form: ``"free"`` predicts the K channels directly (KE18, unbounded); ``"cone"`` predicts per
  pixel a bent normal and the cosine of a visibility cone's half-angle and forms the transport in
  closed form (:func:`relightnet.sh.cone_transport`: the clamped cosine seen through a cone is
  zonal), so every prediction is the transport of *some* surface orientation and occlusion;
- ``albedo`` (B, 3, H, W): linear albedo in (0, 1) (sigmoid);
- ``light`` (B, K, 3): the scene's SH light (camera-relative light frame). ``light_mode``
  chooses how: ``"head"`` regresses it from the pooled bottleneck and decoder features (KE18);
  ``"solve"`` solves it from the predicted maps — the light that makes A ⊙ (T · L) explain the
  image over the person, weighted by a predicted per-pixel confidence
  (:mod:`relightnet.sh.light_solve`); ``"hybrid"`` solves with the head's light as the
  prior. Any batch size and any H, W that are multiples of 16 (no fixed reshape as in KE18);
- optionally ``mask`` (B, 1, H, W) logits, so the 2D path runs without a user mask.

``encoder="pose"`` adds, at every level of the encoder, the projected features of MediaPipe's pose
network (trained on photographs of real people; :mod:`.pose_features`) to the network's own.
``work_scale=2`` runs the CNN at half resolution and brings its raw maps back by a trainable fast
guided filter, guided by the full-resolution input (:mod:`.guided`); the light solve runs at full size.

Normalisation (``normalize_input``) is KE18's: the 8-bit sRGB image mapped to [−1, 1] and
multiplied by the mask, with the mask as a fourth input channel. Images are RGB everywhere
inside relightnet; BGR only exists in Kanamori–Endo light files (see relightnet.sh.io).
GroupNorm keeps the network independent of the batch size.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Literal, get_args

import torch
from torch import nn
from torch.nn import functional as F

from ..checks import InputError, ShapeError, check_choices, check_shape
from ..color import srgb_to_linear
from ..raster.interpolate import to_channels_first, to_channels_last
from ..sh.irradiance import cone_transport
from ..sh.light_solve import Evidence, light_evidence, solve_light
from .guided import FastGuidedUpsample, double_to, pool_input
from .maps import shading_map

__all__ = ["LightMode", "TransportHead", "Encoder", "LIGHT_MODES", "TRANSPORT_HEADS", "ENCODERS", "cone_maps",
           "DEFAULT_INPUT_SIZE", "NetConfig", "Prediction", "RelightNet", "normalize_input"]


#: How the network gets its light (see the module docstring).
LightMode = Literal["head", "solve", "hybrid"]
#: How the network forms its transport (see the module docstring).
TransportHead = Literal["free", "cone"]
#: What the network reads the person with (see the module docstring).
Encoder = Literal["own", "pose"]
#: The choices of :data:`LightMode`, as a tuple.
LIGHT_MODES = get_args(LightMode)
#: The choices of :data:`TransportHead`.
TRANSPORT_HEADS = get_args(TransportHead)
#: The choices of :data:`Encoder`.
ENCODERS = get_args(Encoder)
#: Working size of a network whose checkpoint does not say what it was trained at.
DEFAULT_INPUT_SIZE = 256


@dataclass(frozen=True)
class NetConfig:
    """Architecture: ``width`` channels at full resolution, doubled per level up to ``max_width``;
    ``light_mode`` ``head``, ``solve`` or ``hybrid`` and ``transport_head`` ``free`` or ``cone`` (module
    docstring), ``solve_reg`` the solve's λ; ``encoder`` ``own`` or ``pose`` (the shipped pose network's
    features added at every level, :mod:`.pose_features`; frozen, or trained after the stride
    ``encoder_train_after``).

    ``work_scale`` 2 runs the CNN at half resolution, its maps brought back by guided upsampling (:mod:`.guided`).
    ``input_size`` is not part of the architecture (any H, W that are multiples of 16 run): it is
    the side of the square crops the network was trained on, its working size at inference
    (training sets it from the data; a checkpoint stores it). Predictors read it from here.
    """

    lmax: int = 2
    width: int = 32
    max_width: int = 256
    levels: int = 4
    mask_head: bool = True
    light_hidden: int = 256
    light_mode: LightMode = "head"
    solve_reg: float = 1e-2
    input_size: int = DEFAULT_INPUT_SIZE
    transport_head: TransportHead = "free"
    encoder: Encoder = "own"
    encoder_train_after: int = 0
    work_scale: int = 1

    def __post_init__(self) -> None:
        check_choices(self, "net config")  # light_mode, transport_head, encoder
        if self.encoder_train_after not in (0, 2, 4, 8, 16):
            raise InputError("net config encoder_train_after: expected 0 (frozen) or a stride 2, 4, 8 or 16 of "
                             f"the pose network after which it trains, got {self.encoder_train_after!r}")
        if self.encoder == "pose" and self.levels > 4:
            raise InputError(f"net config levels: the pose encoder has 4 levels below the first, got {self.levels}")
        if self.work_scale not in (1, 2) or isinstance(self.work_scale, bool):
            raise InputError(f"net config work_scale: expected 1 (full resolution) or 2, got {self.work_scale!r}")
        if not self.solve_reg > 0:
            raise InputError(f"net config solve_reg: expected > 0, got {self.solve_reg!r}")
        if isinstance(self.input_size, bool) or not isinstance(self.input_size, int) or self.input_size < 1:
            raise InputError(f"net config input_size: expected a size in pixels, got {self.input_size!r}")

    @property
    def n_coeffs(self) -> int:
        return (self.lmax + 1) ** 2

    @property
    def multiple(self) -> int:
        return 2**self.levels


@dataclass(frozen=True, eq=False)
class Prediction:
    """What the network predicts (CNN layout, channels first).

    Attributes:
        albedo: (B, 3, H, W) linear albedo.
        transport: (B, K, H, W) SH transport.
        light: (B, K, 3) SH light, linear RGB, camera-relative light frame.
        mask: (B, 1, H, W) probability of "person", or None without a mask head.
        evidence: the solve's normal equations (``M`` (B, 3, K, K), ``r`` (B, 3, K)) when the
            light is solved (pooled over frames to share a light across a shot), else None.
        light_head: (B, K, 3) the light head's estimate (``hybrid``: the solve's prior), or None.
        confidence: (B, 1, H, W) the solve's per-pixel weights, or None.
    """

    albedo: torch.Tensor
    transport: torch.Tensor
    light: torch.Tensor
    mask: torch.Tensor | None = None
    evidence: Evidence | None = None
    light_head: torch.Tensor | None = None
    confidence: torch.Tensor | None = None

    def shading(self, light: torch.Tensor | None = None) -> torch.Tensor:
        """(B, 3, H, W) S = T · L with the predicted or a given (K, 3) / (B, K, 3) light."""
        return shading_map(self.transport, self.light if light is None else light)


def cone_maps(raw: torch.Tensor, lmax: int) -> torch.Tensor:
    """Transport maps from a cone head's raw output (:func:`relightnet.sh.cone_transport`).

    Args:
        raw: (B, 4, H, W): three channels of an unnormalised bent normal (light frame) and the logit
            of the cosine of the visibility cone's half-angle (sigmoid: c in (0, 1)).
        lmax: SH order.

    Returns:
        (B, K, H, W) transport.
    """
    check_shape(raw, ["B", 4, "H", "W"], name="cone head output")
    axis = F.normalize(raw[:, :3].float(), dim=1, eps=1e-6)
    c = torch.sigmoid(raw[:, 3].float())
    return to_channels_first(cone_transport(to_channels_last(axis), c, lmax, check=False))


def normalize_input(image: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """KE18 input: sRGB image in [0, 1] → [−1, 1], times the mask, mask appended.

    Args:
        image: (B, 3, H, W) sRGB in [0, 1] (uint8 is divided by 255).
        mask: (B, 1, H, W) or (B, H, W) in [0, 1].

    Returns:
        (B, 4, H, W).
    """
    dims = check_shape(image, ["B", 3, "H", "W"], name="image")
    if mask.dim() == 3:
        mask = mask[:, None]
    check_shape(mask, [dims["B"], 1, dims["H"], dims["W"]], name="mask")
    if image.dtype == torch.uint8:
        image = image.float() / 255
    mask = mask.to(image.dtype)
    return torch.cat([(image * 2 - 1) * mask, mask], 1)


def _norm(c: int) -> nn.GroupNorm:
    return nn.GroupNorm(min(8, c // 4) if c >= 8 else 1, c)


class _Block(nn.Sequential):
    def __init__(self, cin: int, cout: int, stride: int = 1) -> None:
        super().__init__(
            nn.Conv2d(cin, cout, 3, stride, 1, bias=False), _norm(cout), nn.SiLU(inplace=True),
            nn.Conv2d(cout, cout, 3, 1, 1, bias=False), _norm(cout), nn.SiLU(inplace=True),
        )


class _Decoder(nn.Module):
    def __init__(self, widths: list[int], out: int, doubling: bool = False) -> None:
        super().__init__()
        self.doubling = doubling
        rev = widths[::-1]
        self.ups = nn.ModuleList(_Block(rev[i] + rev[i + 1], rev[i + 1]) for i in range(len(rev) - 1))
        self.head = nn.Conv2d(rev[-1], out, 3, 1, 1)

    def forward(self, feats: list[torch.Tensor]) -> tuple[torch.Tensor, list[torch.Tensor]]:
        x = feats[-1]
        inner = []
        for up, skip in zip(self.ups, feats[-2::-1], strict=True):
            x = double_to(x, skip) if self.doubling else F.interpolate(x, size=skip.shape[-2:], mode="bilinear",
                                                                        align_corners=False)
            x = up(torch.cat([x, skip], 1))
            inner.append(x)
        return self.head(x), inner


class RelightNet(nn.Module):
    """Encoder–decoder predicting albedo, transport, light (and a mask)."""

    def __init__(self, config: NetConfig | None = None) -> None:
        super().__init__()
        self.config = cfg = config or NetConfig()
        widths = [min(cfg.width * 2**i, cfg.max_width) for i in range(cfg.levels + 1)]
        self.widths = widths
        self.stem = _Block(4, widths[0])
        self.pose = None
        if cfg.encoder == "pose":
            from .pose_features import PoseFeatures

            self.pose = PoseFeatures(widths, train_after=cfg.encoder_train_after or None, upsample=2 // cfg.work_scale)
        self.down = nn.ModuleList(_Block(widths[i], widths[i + 1], stride=2) for i in range(cfg.levels))
        k = cfg.n_coeffs
        self.solves = cfg.light_mode != "head"
        self.transport_channels = 4 if cfg.transport_head == "cone" else k  # cone: bent normal (3) + aperture
        lowres = cfg.work_scale > 1
        self.transport_dec = _Decoder(widths, self.transport_channels + (1 if self.solves else 0), lowres)  # + conf.
        if cfg.transport_head == "cone":
            with torch.no_grad():  # start at cones facing the camera (light-frame x), half-open (c ≈ 0.18)
                self.transport_dec.head.bias[:4] = torch.tensor([1.0, 0.0, 0.0, -1.5])
        self.albedo_dec = _Decoder(widths, 3 + (1 if cfg.mask_head else 0), lowres)
        # At half resolution: guided upsampling of the raw maps (before normalisation and sigmoids).
        self.up_t = FastGuidedUpsample(self.transport_dec.head.out_channels, cfg.work_scale) if lowres else None
        self.up_a = FastGuidedUpsample(self.albedo_dec.head.out_channels, cfg.work_scale) if lowres else None
        pooled = widths[-1] + sum(widths[:-1])
        self.light_head = None
        if cfg.light_mode != "solve":
            self.light_head = nn.Sequential(
                nn.Linear(pooled, cfg.light_hidden), nn.SiLU(inplace=True), nn.Linear(cfg.light_hidden, k * 3)
            )

    def forward(self, x: torch.Tensor) -> Prediction:
        """Args: x (B, 4, H, W) from :func:`normalize_input`, H and W multiples of 2**levels.

        Returns:
            :class:`Prediction`.
        """
        m = self.config.multiple
        if x.dim() != 4 or x.shape[1] != 4:
            raise ShapeError(f"input: expected (B, 4, H, W) from normalize_input, got {tuple(x.shape)}")
        if x.shape[-2] % m or x.shape[-1] % m:
            raise InputError(
                f"input: H and W must be multiples of {m}, got {tuple(x.shape[-2:])} (use pad_to_multiple)"
            )
        full, s = x, self.config.work_scale
        if s > 1:  # the CNN at 1/s, the pose network (at twice the CNN's size) on the full-size input
            x = pool_input(full, s)
        feats = [self.stem(x)]
        extra = self.pose(full) if self.pose is not None else None
        if extra is not None:
            feats[0] = feats[0] + extra[0]
        for i, d in enumerate(self.down):
            feats.append(d(feats[-1]) if extra is None else d(feats[-1]) + extra[i + 1])
        out, t_inner = self.transport_dec(feats)
        a, a_inner = self.albedo_dec(feats)
        if s > 1:
            out, a = self.up_t(out, full), self.up_a(a, full)
        k, tc = self.config.n_coeffs, self.transport_channels
        transport = cone_maps(out[:, :tc], self.config.lmax) if self.config.transport_head == "cone" else out[:, :k]
        albedo = torch.sigmoid(a[:, :3])
        mask = torch.sigmoid(a[:, 3:4]) if self.config.mask_head else None
        head = None
        if self.light_head is not None:
            # Pooled bottleneck + pooled decoder features (both decoders see the whole person).
            pooled = [feats[-1].mean((2, 3))] + [(t + u).mean((2, 3)) for t, u in zip(t_inner, a_inner, strict=True)]
            head = self.light_head(torch.cat(pooled, 1)).view(x.shape[0], k, 3)
        if not self.solves:
            return Prediction(albedo=albedo, transport=transport, light=head, mask=mask)
        return self._solve(full, albedo, transport, out[:, tc:], head, mask)

    def _solve(self, x, albedo, transport, conf_logit, head, mask) -> Prediction:
        """The light that makes the maps explain the input image (module docstring)."""
        m = x[:, 3:4].float()
        person = (m > 0.5).float()
        srgb = (x[:, :3].float() / m.clamp_min(1e-3) + 1) / 2  # undo normalize_input inside the person
        weight = person * F.softplus(conf_logit.float() + 0.5413)  # 1 at a zero logit
        # The solve runs in float32 whatever the network's precision (bf16 autocast in training).
        fp32 = torch.autocast(x.device.type, enabled=False) if torch.is_autocast_enabled(x.device.type) \
            else contextlib.nullcontext()
        with fp32:
            ev = light_evidence(srgb_to_linear(srgb.clamp(0, 1)), albedo, transport, weight)
            light = solve_light(ev, head.float() if head is not None else None, self.config.solve_reg)
        return Prediction(albedo=albedo, transport=transport, light=light, mask=mask, evidence=ev,
                          light_head=head, confidence=weight)
