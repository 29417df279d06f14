"""What a training run leaves besides its checkpoints: the loss curves, and the check that DDP replicas agree."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import torch

from ..io import atomic_write

logger = logging.getLogger(__name__)

__all__ = ["check_ranks_in_sync", "plot_losses"]


def check_ranks_in_sync(model: torch.nn.Module) -> None:
    """Raise if the replicas' parameters differ across ranks (DDP must keep them equal)."""
    flat = torch.cat([p.detach().reshape(-1).double() for p in model.parameters()])
    mine = torch.stack([flat.sum(), (flat * torch.arange(flat.numel(), dtype=flat.dtype) % 9973).sum()])
    gathered = [torch.zeros_like(mine) for _ in range(torch.distributed.get_world_size())]
    torch.distributed.all_gather(gathered, mine)
    if any(not torch.equal(g, gathered[0]) for g in gathered):
        raise RuntimeError(f"DDP ranks diverged: parameter checksums {[g.tolist() for g in gathered]}")
    logger.info("ranks in sync: %d replicas, parameter checksum %.6e", len(gathered), float(mine[0]))


def plot_losses(log_path, png_path) -> None:
    """Loss curves (total and terms) from a metrics JSONL, as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [json.loads(line) for line in Path(log_path).read_text().splitlines() if line.strip()]
    if not rows:
        return
    fig, ax = plt.subplots(figsize=(8, 4.5))
    steps = np.array([r["step"] for r in rows])
    for key in ("total", "transport", "albedo", "light", "shading_tl", "render_al"):
        if key in rows[0]:
            ax.plot(steps, [r[key] for r in rows], label=key, lw=2 if key == "total" else 1)
    ax.set_yscale("log")
    ax.set_xlabel("step")
    ax.set_ylabel("loss")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    with atomic_write(png_path) as f:
        fig.savefig(f, format="png", dpi=100)
    plt.close(fig)
