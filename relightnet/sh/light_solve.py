"""The light as a solve: the SH light that makes the predicted maps explain the image.

With the image I (linear), albedo A, transport T and per-pixel weights w, the light of
channel c minimises a confidence-weighted, regularised least squares

    Σ_p w_p (I_pc − A_pc Σ_k T_pk L_kc)² + λ s_c ‖L_c − L⁰_c‖²,

whose normal equations are K × K per channel: with a_p = A_pc T_p,
``M_c = Σ_p w_p a_p a_pᵀ / N`` and ``r_c = Σ_p w_p a_p I_pc / N`` (N the number of person
pixels), ``L_c = (M_c + λ s_c 1)⁻¹ (r_c + λ s_c L⁰_c)`` with ``s_c = tr(M_c) / K`` so that λ
does not depend on the exposure. L⁰ is a prior light (zero, or the network's light head in
the hybrid). Everything is differentiable, so the network is trained end to end through the
solve; the K × K system is solved by an unrolled Cholesky factorisation (a fixed number of
tensor ops, so it exports to ONNX and runs the same in torch and ONNX Runtime).

Precision: the normal equations are accumulated and factorised in float64, after scaling M to
a unit diagonal (equilibration). A person seen from one side has normals on a hemisphere, where
the SH functions are close to linearly dependent: M's condition number reaches 10⁵–10⁷ at a
small λ, and a float32 solve then answers with errors of 10⁻² that depend on the summation
order of the CPU's matmul kernels. In float64 the same error is ~10⁻⁹, the same on every CPU.
The evidence stays float64 wherever it travels (pooling, light-sequence files, the ONNX
graph's evidence outputs); only the streaming smoother's state in the ONNX graph stores it
in float32 (:mod:`relightnet.temporal.pooling`), solved in float64 all the same.

Evidence adds up: the normal equations of several frames under the same light are summed
before one solve (:func:`pool_evidence`), which is how a video shares its light across a shot
(:mod:`relightnet.temporal.pooling`).
"""

from __future__ import annotations

import torch

from ..checks import check_shape

__all__ = ["Evidence", "light_evidence", "spd_solve", "solve_light", "pool_evidence", "stack_evidence"]


class Evidence(tuple):
    """Normal equations of a light solve: ``(M (B, 3, K, K), r (B, 3, K))`` (a plain tuple)."""

    __slots__ = ()

    def __new__(cls, M: torch.Tensor, r: torch.Tensor):
        return super().__new__(cls, (M, r))

    @property
    def M(self) -> torch.Tensor:  # noqa: N802
        return self[0]

    @property
    def r(self) -> torch.Tensor:
        return self[1]


def light_evidence(image: torch.Tensor, albedo: torch.Tensor, transport: torch.Tensor,
                   weight: torch.Tensor) -> Evidence:
    """Per-channel normal equations of I ≈ A ⊙ (T · L) over the weighted pixels.

    Args:
        image: (B, 3, H, W) linear RGB.
        albedo: (B, 3, H, W).
        transport: (B, K, H, W).
        weight: (B, 1, H, W) non-negative pixel weights (mask × confidence).

    Returns:
        :class:`Evidence` ``M`` (B, 3, K, K), ``r`` (B, 3, K), averaged over the person's pixels
        (``weight > 0``), float64 whatever the inputs' dtype (module docstring: precision).
    """
    dims = check_shape(transport, ["B", "K", "H", "W"], name="transport")
    b, h, w = dims["B"], dims["H"], dims["W"]
    check_shape(image, [b, 3, h, w], name="image")
    check_shape(albedo, [b, 3, h, w], name="albedo")
    check_shape(weight, [b, 1, h, w], name="weight")
    image, albedo, transport, weight = (t.double() for t in (image, albedo, transport, weight))
    n = (weight > 0).double().sum((2, 3)).clamp_min(1.0)[:, :, None]  # (B, 1, 1)
    # Sums over the pixels without flattening them (an ONNX graph then keeps every shape inferable).
    # Two operands at a time: ONNX Runtime runs a three-operand float64 Einsum slowly (20 ms of a
    # 256² frame's 150).
    v = (weight * albedo * albedo)[:, :, None] * transport[:, None]  # (B, 3, K, H, W)
    M = torch.einsum("bckhw,blhw->bckl", v, transport) / n[..., None]
    r = torch.einsum("bchw,bkhw->bck", weight * albedo * image, transport) / n
    return Evidence(M, r)


def _diagonal(A: torch.Tensor) -> torch.Tensor:
    """(..., K, K) → (..., K), through a constant identity: exported to ONNX as a product and a sum
    whose shapes inference can follow (``Tensor.diagonal`` exports as a shape computed at run time)."""
    k = int(A.shape[-1])
    return (A * torch.eye(k, dtype=A.dtype, device=A.device)).sum(-1)


def spd_solve(A: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Solve A x = b for symmetric positive definite A by an unrolled Cholesky factorisation.

    A is first scaled to a unit diagonal (D A D y = D b, x = D y with D = diag(A)^-1/2), which
    leaves the answer unchanged and makes the factorisation's rounding depend on the scaled
    matrix's condition number, not on how unequal the rows are. K is fixed by the shape, so
    the loops unroll to a fixed graph (ONNX export works) and autograd differentiates through
    them. The arithmetic is in A's dtype (the light solve gives float64).

    Args:
        A: (..., K, K) SPD.
        b: (..., K).

    Returns:
        (..., K).
    """
    k = A.shape[-1]
    d = _diagonal(A).clamp_min(torch.finfo(A.dtype).tiny).rsqrt()  # (..., K)
    A = A * d[..., :, None] * d[..., None, :]
    b = b * d
    cols: list[torch.Tensor] = []  # columns of the lower factor G (A = G Gᵀ)
    for j in range(k):
        v = A[..., :, j]
        for i in range(j):
            v = v - cols[i] * cols[i][..., j : j + 1]
        piv = v[..., j : j + 1].clamp_min(1e-12).sqrt()
        mask = (torch.arange(k, device=A.device) >= j).to(A.dtype)
        cols.append(v / piv * mask)
    G = torch.stack(cols, -1)  # (..., K, K), G[..., i, j] = cols[j][i]
    y: list[torch.Tensor] = []  # forward substitution G y = b
    for i in range(k):
        s = b[..., i]
        for j in range(i):
            s = s - G[..., i, j] * y[j]
        y.append(s / G[..., i, i])
    x: list[torch.Tensor | None] = [None] * k  # back substitution Gᵀ x = y
    for i in reversed(range(k)):
        s = y[i]
        for j in range(i + 1, k):
            s = s - G[..., j, i] * x[j]
        x[i] = s / G[..., i, i]
    return torch.stack(x, -1) * d


def solve_light(evidence: Evidence, prior: torch.Tensor | None = None, reg: float = 1e-2) -> torch.Tensor:
    """The light from (pooled) normal equations, regularised toward a prior.

    Args:
        evidence: :class:`Evidence` with ``M`` (B, 3, K, K) and ``r`` (B, 3, K).
        prior: (B, K, 3) prior light L⁰ (None: zero).
        reg: λ, relative to the mean diagonal of each channel's M.

    Returns:
        (B, K, 3) light, float32 (solved in float64: module docstring).

    Example:
        An image rendered as A ⊙ (T · L) gives its light back (a tiny λ: the solve is nearly exact):

        >>> import torch
        >>> from relightnet.sh import light_evidence, solve_light
        >>> g = torch.Generator().manual_seed(0)
        >>> T = torch.randn(1, 9, 8, 8, generator=g)
        >>> A = torch.rand(1, 3, 8, 8, generator=g)
        >>> L = torch.randn(1, 9, 3, generator=g)
        >>> image = A * torch.einsum("bkhw,bkc->bchw", T, L)
        >>> ev = light_evidence(image, A, T, torch.ones(1, 1, 8, 8))
        >>> ev.M.shape, ev.r.shape
        (torch.Size([1, 3, 9, 9]), torch.Size([1, 3, 9]))
        >>> torch.allclose(solve_light(ev, reg=1e-8), L, atol=1e-4)
        True
    """
    M, r = (x.double() for x in evidence)
    dims = check_shape(M, ["B", 3, "K", "K"], name="evidence M")
    check_shape(r, [dims["B"], 3, dims["K"]], name="evidence r")
    k = dims["K"]
    eye = torch.eye(k, dtype=M.dtype, device=M.device)
    s = _diagonal(M).mean(-1, keepdim=True).clamp_min(1e-8)  # (B, 3, 1)
    rhs = r
    if prior is not None:
        check_shape(prior, [dims["B"], k, 3], name="prior")
        rhs = r + reg * s * prior.transpose(1, 2).to(r)
    return spd_solve(M + reg * s[..., None] * eye, rhs).transpose(1, 2).float()


def pool_evidence(evidence: Evidence, weights: torch.Tensor) -> Evidence:
    """Weighted sums of per-frame normal equations: one solve for several frames.

    Args:
        evidence: per-frame :class:`Evidence`, ``M`` (T, 3, K, K), ``r`` (T, 3, K).
        weights: (T', T) how much frame t counts for output t' (e.g. a window inside a shot).

    Returns:
        :class:`Evidence` with leading dimension T', float64.
    """
    M, r = (x.double() for x in evidence)
    check_shape(weights, ["U", M.shape[0]], name="pooling weights")
    w = weights.to(M)
    return Evidence(torch.einsum("ut,tckl->uckl", w, M), torch.einsum("ut,tck->uck", w, r))


def stack_evidence(evidence: list, priors: list) -> tuple[Evidence | None, torch.Tensor | None]:
    """Per-frame solve outputs of a video → one sequence (evidence float64, priors float32, on the CPU).

    Args:
        evidence: T per-frame :class:`Evidence` (``M`` (1, 3, K, K), ``r`` (1, 3, K)) or None.
        priors: T per-frame prior lights (K, 3) or None.

    Returns:
        ``(Evidence (M (T, 3, K, K), r (T, 3, K)) | None, priors (T, K, 3) | None)``: None when
        any frame has none (a network that regresses its light; no prior for ``light_mode="solve"``).
    """
    if not evidence or any(e is None for e in evidence):
        return None, None
    ev = Evidence(*(torch.cat([e[i] for e in evidence]).double().cpu() for i in (0, 1)))
    return ev, (None if any(p is None for p in priors) else torch.stack(priors).float().cpu())
