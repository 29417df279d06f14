"""ONNX export of the CNN with a streaming light-smoothing layer inside the graph.

The exported graph is one step of a stream (loop-free, so any video length works):

    inputs : image (B, 3, H, W) float32 sRGB in [0, 1], mask (B, 1, H, W) float32,
             light_state (B, S, K, 3) float32, is_first (B,) bool
    outputs: albedo (B, 3, H, W), transport (B, K, H, W), light_raw (B, K, 3),
             light_smoothed (B, K, 3), light_state_out (B, S, K, 3)

B, H and W are dynamic (H, W multiples of 16; of 32 for a network at half resolution, ``work_scale`` 2).
``is_first`` starts a new sequence (the smoother's state is ignored and reset). A network that solves
its light adds three outputs, the solve's per-frame evidence ``evidence_M`` (B, 3, K, K),
``evidence_r`` (B, 3, K) (both float64) and ``light_prior`` (B, K, 3) (zeros without a prior), so that a
whole video can be pooled offline; its ``pooled`` smoother pools the evidence inside the graph
(:class:`relightnet.temporal.pooling.PooledSolve`). The smoother is any module with
``forward(x (B, K, 3), state (B, S, K, 3), is_first (B,)) -> (y, new_state)`` and an int
attribute ``state_size`` (S); ``"none"`` passes the raw light through (S = 1).
"""

from __future__ import annotations

import hashlib
import json
import logging
from pathlib import Path

import torch
from torch import nn

from ..checks import InputError
from ..io import atomic_write
from ..temporal.registry import make_smoother
from .network import RelightNet, normalize_input

logger = logging.getLogger(__name__)

__all__ = ["StreamingRelighter", "export_onnx", "INPUTS", "OUTPUTS", "EVIDENCE_OUTPUTS"]

INPUTS = ("image", "mask", "light_state", "is_first")
OUTPUTS = ("albedo", "transport", "light_raw", "light_smoothed", "light_state_out")
EVIDENCE_OUTPUTS = ("evidence_M", "evidence_r", "light_prior")


class StreamingRelighter(nn.Module):
    """The CNN followed by a streaming smoother of its light: one frame per call."""

    def __init__(self, net: RelightNet, smoother: nn.Module) -> None:
        super().__init__()
        self.net, self.smoother = net, smoother

    def forward(self, image, mask, light_state, is_first):
        p = self.net(normalize_input(image, mask))
        if getattr(self.smoother, "uses_evidence", False):
            smoothed, state = self.smoother(p.light, light_state, is_first, evidence=p.evidence, prior=p.light_head)
        else:
            smoothed, state = self.smoother(p.light, light_state, is_first)
        out = (p.albedo, p.transport, p.light, smoothed, state)
        if p.evidence is None:
            return out
        prior = torch.zeros_like(p.light) if p.light_head is None else p.light_head
        return (*out, p.evidence[0], p.evidence[1], prior)


def _metadata(net: RelightNet, smoothing: str, state_size: int, train_config: dict | None) -> dict:
    cfg_text = json.dumps(train_config or {}, sort_keys=True)
    return {
        "relightnet.sh_order": str(net.config.lmax),
        "relightnet.sh_convention": "real orthonormal SH, no Condon-Shortley phase, k=l(l+1)+m, "
                                    "light frame x=toward camera, y=image right, z=up; light (K,3) linear RGB",
        "relightnet.input": "image: sRGB in [0,1] RGB (B,3,H,W); mask (B,1,H,W); normalised inside the graph "
                            "as KE18: (2*image-1)*mask, mask appended; H, W multiples of "
                            f"{16 * net.config.work_scale}",
        "relightnet.smoothing": smoothing,
        "relightnet.light_mode": net.config.light_mode,
        "relightnet.solve_reg": repr(net.config.solve_reg),
        "relightnet.state_size": str(state_size),
        "relightnet.input_size": str(net.config.input_size),
        "relightnet.multiple": str(16 * net.config.work_scale),
        "relightnet.train_config_sha256": hashlib.sha256(cfg_text.encode()).hexdigest(),
    }


def export_onnx(net: RelightNet, out, smoothing: str = "ema", train_config: dict | None = None,
                example_size: int = 64, **smoother_opts) -> Path:
    """Export one self-contained ``.onnx`` file (weights inside, dynamic batch/H/W).

    Args:
        net: the trained network (eval mode).
        out: output path (written atomically).
        smoothing: a causal method (:func:`relightnet.names.smoothing_names` ``(causal=True)``; each can
            live inside the graph, built by :func:`relightnet.temporal.make_smoother`).
        train_config: stored as a hash in the model metadata.
        example_size: H = W of the example used for tracing (a multiple of 16; of 32 at ``work_scale`` 2).

    Returns:
        The path written.
    """
    import onnx

    if Path(out).suffix.lower() != ".onnx":
        raise InputError(f"{out}: expected an .onnx output file")
    mult = 16 * net.config.work_scale  # at half resolution, multiples of 32: every level doubles exactly
    if example_size % mult:
        raise InputError(f"example_size: expected a multiple of {mult}, got {example_size}")
    if smoothing == "pooled":
        if not net.solves:
            raise InputError("smoothing pooled: this network regresses its light (light_mode head); "
                             "pooling needs a solve or hybrid network")
        smoother_opts = {"reg": net.config.solve_reg, **smoother_opts}
    smoother = make_smoother(smoothing, lmax=net.config.lmax, **smoother_opts)
    model = StreamingRelighter(net.eval(), smoother).eval()
    k, s = net.config.n_coeffs, smoother.state_size
    b, hw = 2, example_size
    args = (torch.rand(b, 3, hw, hw), torch.ones(b, 1, hw, hw), torch.zeros(b, s, k, 3),
            torch.ones(b, dtype=torch.bool))
    batch = torch.export.Dim("batch", min=1, max=1024)
    h16, w16 = torch.export.Dim("h16", min=1, max=8192 // mult), torch.export.Dim("w16", min=1, max=8192 // mult)
    spatial = {0: batch, 2: mult * h16, 3: mult * w16}
    shapes = {"image": spatial, "mask": spatial, "light_state": {0: batch}, "is_first": {0: batch}}
    import warnings

    # The exporter's own notes ("torchvision is not installed", onnx_ir/onnxscript pass logs, about
    # a hundred INFO lines) are not the user's business.
    quiet = [logging.getLogger(n) for n in ("torch.onnx", "onnx_ir", "onnxscript")]
    levels = [q.level for q in quiet]
    for q in quiet:
        q.setLevel(logging.ERROR)
    try:
        with warnings.catch_warnings(), torch.no_grad():
            warnings.simplefilter("ignore")
            prog = torch.onnx.export(model, args, dynamo=True, dynamic_shapes=shapes, input_names=list(INPUTS),
                                     output_names=list(OUTPUTS) + (list(EVIDENCE_OUTPUTS) if net.solves else []),
                                     verbose=False)
    finally:
        for q, lv in zip(quiet, levels, strict=True):
            q.setLevel(lv)
    proto = prog.model_proto
    for key, value in _metadata(net, smoothing, s, train_config).items():
        entry = proto.metadata_props.add()
        entry.key, entry.value = key, value
    with atomic_write(out) as f:
        f.write(proto.SerializeToString())
    onnx.checker.check_model(str(out))
    logger.info("wrote %s (smoothing=%s, state (B, %d, %d, 3))", out, smoothing, s, k)
    return Path(out)
