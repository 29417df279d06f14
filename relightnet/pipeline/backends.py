"""Where the CNN runs: PyTorch (eager) or an exported ONNX model in ONNX Runtime.

Both backends are :class:`Predictor` s: ``predictor(image (3, H, W), mask (H, W) | None) -> Prediction``
at the photo's own resolution (crop around the mask, resize to the working size, run, paste
back), ``predictor.crop(image, mask) -> CropMaps`` (the same without the paste: the maps at the
working size, pasted band by band where a large photo is relit,
:class:`~relightnet.model.inference.CropMaps`), ``predictor.light(image, mask) -> (K, 3)`` (the light
only, nothing pasted back),
``predictor.light_evidence(image, mask) -> (light (K, 3), Evidence | None, prior (K, 3) | None)``
(what a video pools over a shot, :mod:`relightnet.temporal.pooling`; None for a network that
regresses its light), ``predictor.lmax`` the SH order of the model, ``predictor.solve_reg``
its light solve's λ, ``predictor.size`` its working size (from the checkpoint's configuration,
:attr:`~relightnet.model.NetConfig.input_size`, or the ONNX file's metadata) and
``predictor.has_mask_head``. The jobs take any predictor (or a :class:`RelightNet`, wrapped).
"""

from __future__ import annotations

import copy
import hashlib
import logging
import os
from pathlib import Path
from typing import Protocol, runtime_checkable

import torch

from ..checks import InputError, sh_order_from_count
from ..model.inference import CropMaps
from ..model.network import Prediction, RelightNet

logger = logging.getLogger(__name__)

__all__ = ["BACKENDS", "Predictor", "TorchPredictor", "OnnxPredictor", "as_predictor", "make_predictor",
           "exported_onnx", "onnx_cache_dir"]

#: Where the CNN runs: PyTorch or ONNX Runtime (``--backend``).
BACKENDS = ("torch", "onnx")


@runtime_checkable
class Predictor(Protocol):
    """What the jobs need from the CNN, whatever runs it (module docstring)."""

    #: SH order of the light.
    lmax: int
    #: working size (side of the square crop the network sees).
    size: int
    #: λ of the network's light solve.
    solve_reg: float
    #: whether ``mask=None`` is accepted (the network finds the person itself).
    has_mask_head: bool

    def __call__(self, image: torch.Tensor, mask: torch.Tensor | None = None) -> Prediction:
        """Albedo, transport, light (and mask) at the photo's resolution, batch 1."""

    def crop(self, image: torch.Tensor, mask: torch.Tensor | None = None) -> CropMaps:
        """The same prediction with its maps at the working size (not pasted back)."""

    def light(self, image: torch.Tensor, mask: torch.Tensor | None = None) -> torch.Tensor:
        """The light (K, 3) only."""

    def light_evidence(self, image: torch.Tensor, mask: torch.Tensor | None = None):
        """``(light (K, 3), Evidence | None, prior (K, 3) | None)``."""


def _check_size(size, multiple: int = 16) -> int:
    if isinstance(size, bool) or not isinstance(size, int) or size < multiple or size % multiple:
        raise InputError(f"size: expected a positive multiple of {multiple}, got {size!r}")
    return size


class TorchPredictor:
    """The CNN in PyTorch. Args: model (eval mode); size: working size (default: its training size,
    ``model.config.input_size``).

    The predictor runs the model with channels-last weights (same results to ~1e-5; about 1.5x
    faster convolutions on CPU): the model itself where its weights are channels-last already, else
    a copy made so (``model`` is left as it was given).
    """

    def __init__(self, model: RelightNet, size: int | None = None) -> None:
        self.model = _channels_last(model)
        self.size = model.config.input_size if size is None else _check_size(size, model.config.multiple)
        self.lmax = model.config.lmax
        self.has_mask_head = bool(model.config.mask_head)
        self.solve_reg = model.config.solve_reg

    def __call__(self, image: torch.Tensor, mask: torch.Tensor | None = None) -> Prediction:
        from ..model.inference import predict_image

        return predict_image(self.model, image, mask, size=self.size)[0]

    def crop(self, image: torch.Tensor, mask: torch.Tensor | None = None) -> CropMaps:
        """The prediction with its maps at the working size (:class:`~relightnet.model.inference.CropMaps`)."""
        from ..model.inference import predict_crop

        return predict_crop(self.model, image, mask, size=self.size)

    def light(self, image: torch.Tensor, mask: torch.Tensor | None = None) -> torch.Tensor:
        """Only the light (K, 3) (the maps are not pasted back)."""
        from ..model.inference import estimate_light

        return estimate_light(self.model, image, mask, size=self.size)

    def light_evidence(self, image: torch.Tensor, mask: torch.Tensor | None = None):
        """``(light (K, 3), evidence | None, prior (K, 3) | None)`` (module docstring)."""
        from ..model.inference import estimate_light_evidence

        return estimate_light_evidence(self.model, image, mask, size=self.size)


def _channels_last(model: torch.nn.Module) -> torch.nn.Module:
    """``model`` where its 4-D weights and buffers are channels-last already, else a channels-last copy."""
    tensors = [*model.parameters(), *model.buffers()]
    if all(t.dim() != 4 or t.is_contiguous(memory_format=torch.channels_last) for t in tensors):
        return model
    return copy.deepcopy(model).to(memory_format=torch.channels_last)


class OnnxPredictor:
    """The exported model in ONNX Runtime (CPU). Masks are required (the graph has no mask head).

    The light returned is the graph's raw per-frame estimate (``light_raw``); jobs smooth it
    themselves.

    Args:
        path: ``.onnx`` file from ``relightnet export``.
        threads: intra-op threads (0: ONNX Runtime's default).
        size: working size (default: the training size stored in the model's metadata).
    """

    def __init__(self, path, threads: int = 0, size: int | None = None) -> None:
        from ..model.onnx_serving import OnnxRelighter

        self.relighter = OnnxRelighter(path, threads=threads)
        self.size = _check_size(self.relighter.input_size if size is None else size, self.relighter.multiple)
        self.lmax = sh_order_from_count(self.relighter.n_coeffs, "ONNX model light")
        self.has_mask_head = False
        self.solve_reg = float(self.relighter.metadata.get("relightnet.solve_reg", 1e-2))
        self._has_prior = self.relighter.metadata.get("relightnet.light_mode") == "hybrid"

    def _step(self, image: torch.Tensor, mask: torch.Tensor | None):
        if mask is None:
            raise InputError("mask: the ONNX backend has no mask head; give the person's masks")
        return self.relighter.step_photo(image, mask, self.size)

    def light(self, image: torch.Tensor, mask: torch.Tensor | None = None) -> torch.Tensor:
        """Only the light (K, 3) (the maps are not pasted back)."""
        return torch.from_numpy(self._step(image, mask)[0]["light_raw"][0])

    def light_evidence(self, image: torch.Tensor, mask: torch.Tensor | None = None):
        """``(light (K, 3), evidence | None, prior (K, 3) | None)`` (module docstring)."""
        res = self._step(image, mask)[0]
        prior = torch.from_numpy(res["light_prior"][0]) if self._has_prior and "light_prior" in res else None
        return torch.from_numpy(res["light_raw"][0]), _evidence(res), prior

    @torch.no_grad()
    def __call__(self, image: torch.Tensor, mask: torch.Tensor | None = None) -> Prediction:
        return self.crop(image, mask).pasted()

    @torch.no_grad()
    def crop(self, image: torch.Tensor, mask: torch.Tensor | None = None) -> CropMaps:
        """The prediction with its maps at the working size (:class:`~relightnet.model.inference.CropMaps`)."""
        res, box = self._step(image, mask)
        return CropMaps(
            albedo=torch.from_numpy(res["albedo"]),
            transport=torch.from_numpy(res["transport"]),
            light=torch.from_numpy(res["light_raw"]),
            mask=mask.float()[None, None],
            box=box,
            evidence=_evidence(res),
            light_head=torch.from_numpy(res["light_prior"]) if self._has_prior and "light_prior" in res else None,
        )


def _evidence(res: dict):
    """The light solve's evidence among an ONNX step's outputs, or None."""
    from ..sh.light_solve import Evidence

    if "evidence_M" not in res:
        return None
    return Evidence(torch.from_numpy(res["evidence_M"]), torch.from_numpy(res["evidence_r"]))


def as_predictor(model, size: int | None = None) -> Predictor:
    """A :class:`Predictor` from a :class:`RelightNet` (wrapped, at ``size`` or its own working size)
    or a predictor (returned as is; its size is set when it is made, ``size`` must be None or agree)."""
    if isinstance(model, RelightNet):
        return TorchPredictor(model, size)
    if isinstance(model, Predictor):
        if size is not None and size != model.size:
            raise InputError(f"size: the predictor works at {model.size}; give size={size} when making it "
                             "(make_predictor(..., size=...))")
        return model
    raise InputError(f"model: expected a RelightNet or a predictor, got {type(model).__name__}")


def onnx_cache_dir() -> Path:
    """Where :func:`exported_onnx` keeps exports by default: ``$RELIGHTNET_CACHE`` or ~/.cache/relightnet."""
    return Path(os.environ.get("RELIGHTNET_CACHE") or Path.home() / ".cache" / "relightnet")


def exported_onnx(checkpoint=None, cache_dir=None) -> Path:
    """The ONNX export of a checkpoint, made once and kept on disk (an explicit, documented cache).

    ``--backend onnx`` with a ``.pt`` checkpoint runs the model exported by ``relightnet export``
    (no smoothing in the graph); the export takes seconds, so it is written once as
    ``CACHE/<checkpoint stem>-<first 16 hex digits of its SHA-256>.onnx`` and reused while the
    checkpoint's content is the same. Delete the folder to drop it.

    Args:
        checkpoint: a ``.pt`` checkpoint (default: the shipped model).
        cache_dir: the folder (default: :func:`onnx_cache_dir`).

    Returns:
        The path of the ``.onnx`` file.
    """
    from ..model.checkpoint import load_checkpoint, load_model, shipped_checkpoint
    from ..model.onnx_export import export_onnx

    ckpt = shipped_checkpoint() if checkpoint is None else Path(checkpoint)
    if not ckpt.is_file():
        raise InputError(f"{ckpt}: checkpoint not found")
    digest = hashlib.sha256(ckpt.read_bytes()).hexdigest()[:16]
    out = Path(onnx_cache_dir() if cache_dir is None else cache_dir) / f"{ckpt.stem}-{digest}.onnx"
    if not out.is_file():
        logger.info("exporting %s to ONNX (once): %s", ckpt, out)
        out.parent.mkdir(parents=True, exist_ok=True)
        state = load_checkpoint(ckpt)
        export_onnx(load_model(ckpt), out, smoothing="none", train_config=state.get("train_config"))
    return out


def make_predictor(backend: str = "torch", checkpoint=None, device: str = "cpu", threads: int = 0,
                   size: int | None = None, cache_dir=None) -> Predictor:
    """A :class:`Predictor` for the jobs.

    Args:
        backend: ``"torch"`` or ``"onnx"``.
        checkpoint: a ``.pt`` checkpoint (default: the shipped model); for ``onnx`` also a
            ``.onnx`` file, else the checkpoint's export (:func:`exported_onnx`, in ``cache_dir``).
        device: torch device (``onnx`` runs on the CPU).
        threads: ONNX Runtime intra-op threads (0: default).
        size: working size, a multiple of 16 (default: the model's training size).
        cache_dir: where :func:`exported_onnx` keeps exports (default: :func:`onnx_cache_dir`).
    """
    from ..model.checkpoint import load_model

    if backend not in BACKENDS:
        raise InputError(f"backend: expected one of {', '.join(BACKENDS)}, got {backend!r}")
    if size is not None:
        _check_size(size)
    if backend == "torch":
        if checkpoint is not None and str(checkpoint).endswith(".onnx"):
            raise InputError(f"{checkpoint}: an ONNX model needs --backend onnx")
        model = load_model(checkpoint, device=device).to(memory_format=torch.channels_last)  # its own: no copy
        return TorchPredictor(model, size)
    if device != "cpu":
        raise InputError(f"device: the onnx backend runs on the CPU, got {device!r}")
    onnx_file = checkpoint is not None and str(checkpoint).endswith(".onnx")
    path = Path(checkpoint) if onnx_file else exported_onnx(checkpoint, cache_dir)
    return OnnxPredictor(path, threads=threads, size=size)
