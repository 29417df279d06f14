"""Training loop of the inverse-rendering CNN: deterministic, resumable, optionally distributed.

Everything that decides a run is in :class:`~relightnet.model.train_config.TrainConfig` (YAML). The data order is a pure
function of (seed, step): epoch ``e`` shuffles the training items with a generator seeded
by (seed, e) and each item's augmentation draws from a generator seeded by (seed, e, item).
A checkpoint therefore only needs the model, optimiser, scheduler and step to continue
bit-identically. Under ``torchrun`` (``WORLD_SIZE`` > 1) the loop runs DistributedDataParallel
(gloo on CPU, nccl on CUDA); rank r takes the r-th slice of every global batch and only
rank 0 writes files.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import json
import logging
import math
import os
import time
from pathlib import Path

import torch

from ..checks import InputError
from ..color import linear_to_srgb
from ..threads import torch_threads
from .checkpoint import load_checkpoint, save_checkpoint
from .losses import LossWeights, relight_losses
from .maps import shade_map
from .network import NetConfig, RelightNet, normalize_input
from .round_trip import novel_lights, round_trip_loss
from .train_config import TrainConfig, load_train_config
from .train_log import check_ranks_in_sync, plot_losses

logger = logging.getLogger(__name__)

# TrainConfig and load_train_config live in .train_config; the training entry points take them from here too.
__all__ = ["TrainConfig", "load_train_config", "train", "batch_to_input", "TrainData", "save_candidate",
           "CANDIDATE_BYTES"]


class TrainData:
    """The training split held in memory (only the fields training needs).

    Args:
        root: dataset folder made by ``relightnet synth``.
        split: which split.
        target: transport field to learn.
        dtype: how the maps are held in memory (``torch.float16`` halves it); batches are float32.
        limit: keep the first ``limit`` items only (None: all).
    """

    FIELDS = ("image", "mask", "albedo", "light")

    def __init__(self, root, split: str = "train", target: str = "transport", dtype=torch.float32,
                 limit: int | None = None, extra: tuple = ()) -> None:
        from ..data.dataset import SynthDataset

        ds = SynthDataset(root, split, fields=(*self.FIELDS, target, *extra), cache_shards=1)
        if len(ds) == 0:
            raise InputError(f"{root}: the {split} split is empty")
        self.target = target
        keys = (*self.FIELDS, target, *extra)
        first = ds[0]
        n = len(ds) if limit is None else min(limit, len(ds))
        self.tensors = {k: torch.empty((n, *first[k].shape), dtype=torch.float32 if k == "light" else dtype)
                        for k in keys}
        for i in range(n):  # shard order: each shard is read once
            item = first if i == 0 else ds[i]
            for k in keys:
                self.tensors[k][i] = item[k]
        self.tensors["transport"] = self.tensors.pop(target)
        self.n_coeffs = self.tensors["transport"].shape[1]
        self.size = int(self.tensors["image"].shape[-1])

    def __len__(self) -> int:
        return self.tensors["image"].shape[0]

    def batch(self, idx: torch.Tensor, augment=None, gens: list | None = None) -> dict:
        """Gather items (augmented one by one with their own generators)."""
        out = []
        for j, i in enumerate(idx.tolist()):
            s = {k: v[i].float() for k, v in self.tensors.items()}
            if augment is not None:
                s = augment(s, gens[j])
            out.append(s)
        return {k: torch.stack([s[k] for s in out]) for k in out[0]}


def batch_to_input(batch: dict) -> torch.Tensor:
    """Network input of a batch: ``input`` when the items were framed as photos
    (:class:`~relightnet.model.photo_input.PhotoInput`), else the camera's view (sRGB of the
    linear image) and the mask."""
    if "input" in batch:
        return batch["input"]
    srgb = linear_to_srgb(batch["image"].clamp(0, 1))
    return normalize_input(srgb, batch["mask"])


def _indices(n: int, step: int, batch: int, seed: int, world: int, rank: int) -> tuple[torch.Tensor, int]:
    per_epoch = max(1, n // (batch * world))
    epoch, b = divmod(step, per_epoch)
    perm = torch.randperm(n, generator=torch.Generator().manual_seed(seed * 100003 + epoch))
    if n < batch * world:
        perm = perm.repeat(math.ceil(batch * world / n))
    start = (b * world + rank) * batch
    return perm[start : start + batch], epoch


def _lr_lambda(cfg: TrainConfig):
    def f(step: int) -> float:
        if step < cfg.warmup:
            return (step + 1) / cfg.warmup
        t = (step - cfg.warmup) / max(1, cfg.steps - cfg.warmup)
        return 0.5 * (1 + math.cos(math.pi * min(t, 1.0)))

    return f


def _dist_env() -> tuple[int, int]:
    return int(os.environ.get("RANK", 0)), int(os.environ.get("WORLD_SIZE", 1))


def _new_model(cfg: TrainConfig, data: TrainData, device: str, resume: bool) -> tuple[RelightNet, NetConfig]:
    """The network to train (seeded), its working size ``photo.size`` or the data's; ``cfg.init``'s weights if new."""
    photo = cfg.photo
    size = data.size if photo is None or photo.size is None else photo.size  # items framed down to it
    net_cfg = dataclasses.replace(cfg.net, lmax=int(round(math.sqrt(data.n_coeffs))) - 1, input_size=size)
    torch.manual_seed(cfg.seed)
    model = RelightNet(net_cfg).to(device)
    if cfg.channels_last:
        model = model.to(memory_format=torch.channels_last)
    if cfg.init and not resume:
        init = load_checkpoint(cfg.init, map_location=device)
        init_cfg = NetConfig(**{**init["net_config"], "input_size": net_cfg.input_size})  # sizes may differ
        if init_cfg != net_cfg:
            raise InputError(f"{cfg.init}: its network configuration differs from the training config's")
        model.load_state_dict(init["model"])
    return model, net_cfg


def _resume(ckpt: Path, cfg: TrainConfig, model, opt, sched, device: str) -> int:
    """Restore model, optimiser and schedule from ``ckpt`` (made with the same config): its step.

    A candidate (:func:`save_candidate`) holds no optimiser state: the weights, step and schedule
    continue and Adam's moments start again from zero (logged)."""
    state = load_checkpoint(ckpt, map_location=device)
    # Keys added to TrainConfig later take their defaults in older checkpoints.
    if not isinstance(state.get("train_config"), dict) or not isinstance(state.get("scheduler"), dict):
        raise InputError(f"{ckpt}: not a training checkpoint (no train_config or scheduler state)")
    if TrainConfig.from_dict(state["train_config"], f"{ckpt}: its training config") != cfg:
        raise InputError(f"{ckpt}: the checkpoint was made with a different training config")
    model.load_state_dict(state["model"])
    if "optimizer" in state:
        opt.load_state_dict(state["optimizer"])
    else:
        logger.info("%s: a candidate without optimiser state; Adam's moments restart at step %d", ckpt, state["step"])
    sched.load_state_dict(state["scheduler"])
    return state["step"]


#: Largest candidate checkpoint committed to the repository (train/checkpoints/).
CANDIDATE_BYTES = 15 * 2**20


def save_candidate(path, model: RelightNet, net_cfg: NetConfig, step: int, sched, cfg: TrainConfig,
                   data_dir) -> Path:
    """Write a run's carry-over checkpoint: weights, step, schedule, training config and the data's
    recipe (the ``relightnet synth`` config of ``data_dir``, so a fresh machine regenerates it), no
    optimiser state; at most :data:`CANDIDATE_BYTES`. ``relightnet train --resume-from`` continues it."""
    from ..io.documents import read_document

    manifest = read_document(Path(data_dir) / "manifest.json", "dataset manifest", yaml_ok=False)
    recipe = manifest.get("config") if isinstance(manifest, dict) else None
    path = Path(path)
    new = save_checkpoint(path.with_name(path.name + ".new"), model, net_cfg, step=step, scheduler=sched,
                          train_config=cfg.to_dict(), data_recipe=recipe if isinstance(recipe, dict) else {})
    if new.stat().st_size > CANDIDATE_BYTES:  # the previous candidate stays as it was
        new.unlink()
        raise InputError(f"{path}: the candidate is larger than {CANDIDATE_BYTES >> 20} MB; use a smaller network")
    os.replace(new, path)
    return path


def _step_terms(cfg: TrainConfig, model, batch: dict, weights: LossWeights, step: int, device: str) -> dict:
    """The loss terms of one step (``batch``, on ``device``, gets ``render`` and ``novel_light`` as the config asks)."""
    if cfg.render_target == "model":
        batch["render"] = shade_map(batch["albedo"], batch["transport"], batch["light"])
    if cfg.novel_light != "batch" or weights.round_trip:
        draws = torch.Generator().manual_seed(cfg.seed * 1000003 + step)
        batch["novel_light"] = novel_lights(batch["light"], cfg.novel_light, draws).to(device)
    x = batch_to_input(batch)
    if cfg.channels_last:
        x = x.contiguous(memory_format=torch.channels_last)
    amp = functools.partial(torch.autocast, torch.device(device).type, dtype=torch.bfloat16,
                            enabled=cfg.precision == "bf16")
    with amp():  # the network's passes only: the losses stay float32
        pred = model(x)
    terms = relight_losses(pred, batch, weights)
    if weights.round_trip:
        with amp():
            terms["round_trip"] = round_trip_loss(model, x, pred, batch["novel_light"])
        terms["total"] = terms["total"] + weights.round_trip * terms["round_trip"]
    return terms


def train(cfg: TrainConfig, data_dir, out_dir, resume: bool = False, device: str = "cpu",
          stop_after: int | None = None, resume_from=None, candidate=None) -> dict:
    """Train (or continue training) a :class:`RelightNet`.

    Args:
        cfg: the run's configuration.
        data_dir: dataset folder (``relightnet synth``).
        out_dir: run folder: ``last.pt`` (atomic checkpoints), ``metrics.jsonl``, ``loss.png``.
        resume: continue from ``out_dir/last.pt`` (bit-identical continuation).
        device: ``cpu`` or ``cuda``.
        stop_after: stop (with a checkpoint) after this many steps of this call, for tests.
        resume_from: continue from this checkpoint instead (a run's ``last.pt`` or a committed
            candidate) when ``out_dir`` has no ``last.pt`` yet; the same training config is required.
        candidate: also write the carry-over checkpoint here at every checkpoint (:func:`save_candidate`).

    Returns:
        The last logged metrics.

    ``cfg.threads`` (when set) is torch's thread count for the run; the caller's count is restored afterwards.
    """
    with torch_threads(cfg.threads) if cfg.threads else contextlib.nullcontext():
        return _train(cfg, data_dir, out_dir, resume, device, stop_after, resume_from, candidate)


def _train(cfg: TrainConfig, data_dir, out_dir, resume, device, stop_after, resume_from, candidate) -> dict:
    """:func:`train`'s run, on the thread count it set."""
    rank, world = _dist_env()
    weights = cfg.loss
    if world > 1 and weights.round_trip:  # DDP marks a parameter ready once per backward
        raise InputError("train config loss.round_trip: a second pass per step is not supported under torchrun")
    if world > 1 and not torch.distributed.is_initialized():
        torch.distributed.init_process_group("nccl" if device.startswith("cuda") else "gloo")
    out = Path(out_dir)
    if rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    data, aug = _data_and_augment(cfg, data_dir)
    model, net_cfg = _new_model(cfg, data, device, resume or resume_from is not None)
    opt = torch.optim.AdamW(model.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    sched = torch.optim.lr_scheduler.LambdaLR(opt, _lr_lambda(cfg))
    ckpt = out / "last.pt"
    source = ckpt if resume or (resume_from is not None and ckpt.exists()) else resume_from
    step = _resume(Path(source), cfg, model, opt, sched, device) if source is not None else 0
    ddp = torch.nn.parallel.DistributedDataParallel(model) if world > 1 else model
    log_path = out / "metrics.jsonl"
    last: dict = {}
    t0, done_here = time.perf_counter(), 0
    while step < cfg.steps and (stop_after is None or done_here < stop_after):
        idx, epoch = _indices(len(data), step, cfg.batch_size, cfg.seed, world, rank)
        gens = [torch.Generator().manual_seed(cfg.seed * 7919 + epoch * 104729 + int(i)) for i in idx]
        batch = {k: v.to(device) for k, v in data.batch(idx, aug, gens).items()}
        terms = _step_terms(cfg, ddp, batch, weights, step, device)
        opt.zero_grad(set_to_none=True)
        terms["total"].backward()
        opt.step()
        sched.step()
        step += 1
        done_here += 1
        if rank == 0 and (step % cfg.log_every == 0 or step == cfg.steps):
            dt = time.perf_counter() - t0
            last = {"step": step, "lr": sched.get_last_lr()[0],
                    "samples_per_s": done_here * cfg.batch_size * world / dt,
                    **{k: float(v.detach()) for k, v in terms.items()}}
            with open(log_path, "a") as f:
                f.write(json.dumps(last) + "\n")
            logger.info("step %d/%d loss %.4f (%.1f samples/s)", step, cfg.steps, last["total"], last["samples_per_s"])
        if rank == 0 and (step % cfg.checkpoint_every == 0 or step == cfg.steps
                          or (stop_after is not None and done_here == stop_after)):
            save_checkpoint(ckpt, model, net_cfg, step=step, optimizer=opt, scheduler=sched,
                            train_config=cfg.to_dict(), data=str(data_dir))
            if candidate is not None:
                save_candidate(candidate, model, net_cfg, step, sched, cfg, data_dir)
    if rank == 0 and step >= cfg.steps:
        plot_losses(log_path, out / "loss.png")
    if world > 1:
        check_ranks_in_sync(model)
        torch.distributed.barrier()
    return last


def _data_and_augment(cfg: TrainConfig, data_dir):
    """The training split in memory and the per-item transform (augmentation, then the photo framing)."""
    from ..data.augment import Augment

    photo = cfg.photo
    extra = ("image_composite",) if photo is not None and photo.composite > 0 else ()
    data = TrainData(data_dir, "train", cfg.target, getattr(torch, cfg.data_dtype), cfg.train_items, extra)
    aug = Augment(**dataclasses.asdict(cfg.augment)) if cfg.augment else None
    return data, (photo.after(aug) if photo is not None else aug)
