import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import torch

from relightnet.checks import InputError
from relightnet.model import load_checkpoint, load_model
from relightnet.model.losses import relight_losses
from relightnet.model.network import Prediction, shading_map
from relightnet.model.training import TrainConfig, load_train_config, train

pytestmark = pytest.mark.slow  # training steps on a generated dataset; torchrun with two processes

REPO = Path(__file__).resolve().parents[2]
NET = {"width": 8, "max_width": 32, "light_hidden": 32}


def _losses(run):
    return [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]


def test_a_few_steps_reduce_the_loss(tiny_dataset, tmp_path):
    cfg = TrainConfig(steps=25, batch_size=3, lr=3e-3, warmup=1, log_every=1, checkpoint_every=25, net=NET,
                      augment={}, threads=2)
    train(cfg, tiny_dataset, tmp_path / "run")
    totals = [r["total"] for r in _losses(tmp_path / "run")]
    assert len(totals) == 25
    assert sum(totals[-5:]) / 5 < 0.8 * sum(totals[:5]) / 5
    assert (tmp_path / "run" / "loss.png").stat().st_size > 1000
    model = load_model(tmp_path / "run" / "last.pt")
    assert model.config.width == 8


def test_resume_continues_bit_identically(tiny_dataset, tmp_path):
    cfg = TrainConfig(steps=4, batch_size=2, warmup=1, log_every=1, checkpoint_every=10, net=NET, threads=1)
    train(cfg, tiny_dataset, tmp_path / "full")
    train(cfg, tiny_dataset, tmp_path / "cut", stop_after=2)  # "killed" after step 2 (checkpoint written)
    assert load_checkpoint(tmp_path / "cut" / "last.pt")["step"] == 2
    train(cfg, tiny_dataset, tmp_path / "cut", resume=True)
    full, cut = _losses(tmp_path / "full"), _losses(tmp_path / "cut")
    assert [r["step"] for r in cut] == [1, 2, 3, 4]
    for a, b in zip(full, cut, strict=True):
        assert a["total"] == b["total"] and a["transport"] == b["transport"]
    other = TrainConfig(steps=5, batch_size=2, warmup=1, net=NET)
    with pytest.raises(InputError, match="different training config"):
        train(other, tiny_dataset, tmp_path / "cut", resume=True)
    # A checkpoint written before a config key existed resumes with that key's default.
    train(cfg, tiny_dataset, tmp_path / "old", stop_after=1)
    state = load_checkpoint(tmp_path / "old" / "last.pt")
    del state["train_config"]["render_target"]
    torch.save(state, tmp_path / "old" / "last.pt")
    train(cfg, tiny_dataset, tmp_path / "old", resume=True)
    assert load_checkpoint(tmp_path / "old" / "last.pt")["step"] == 4


def test_bad_checkpoints_and_configs_fail_clearly(tmp_path, tiny_dataset):
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"not a checkpoint")
    with pytest.raises(InputError, match="unreadable checkpoint"):
        load_model(bad)
    torch.save({"hello": 1}, tmp_path / "other.pt")
    with pytest.raises(InputError, match="not a relightnet checkpoint"):
        load_model(tmp_path / "other.pt")
    cfg = TrainConfig(steps=1, batch_size=2, warmup=1, net=NET)
    train(cfg, tiny_dataset, tmp_path / "r")
    state = load_checkpoint(tmp_path / "r" / "last.pt")
    state["net_config"]["width"] = 16
    torch.save(state, tmp_path / "mismatch.pt")
    with pytest.raises(InputError, match="weights do not match"):
        load_model(tmp_path / "mismatch.pt")
    truncated = tmp_path / "trunc.pt"
    truncated.write_bytes((tmp_path / "r" / "last.pt").read_bytes()[:2000])
    with pytest.raises(InputError, match="unreadable checkpoint"):
        load_model(truncated)
    with pytest.raises(InputError, match="target"):
        TrainConfig(target="normals")
    with pytest.raises(InputError, match="render_target"):
        TrainConfig(render_target="photo")
    (tmp_path / "c.yaml").write_text("steps: 3\nbogus: 1\n")
    with pytest.raises(InputError, match="unknown keys"):
        load_train_config(tmp_path / "c.yaml")


def test_every_config_in_train_configs_loads_with_its_values():
    import yaml

    from relightnet.data import load_config

    configs = sorted((REPO / "train" / "configs").glob("*.yaml"))
    synth = [p for p in configs if p.name.startswith(("data_", "seq_"))]  # the datasets: relightnet synth configs
    train_ = [p for p in configs if p not in synth]
    assert len(train_) >= 10 and {"tiny.yaml", "small.yaml", "clothed_photo_side.yaml"} <= {p.name for p in train_}
    for path in train_:
        raw, cfg = yaml.safe_load(path.read_text()), load_train_config(path)
        for key, value in raw.items():
            if isinstance(value, (int, float, str)):
                assert getattr(cfg, key) == value, (path.name, key)
    for path in synth:
        raw, cfg = yaml.safe_load(path.read_text()), load_config(path)
        assert cfg.res == raw.get("res", cfg.res) and cfg.seed == raw.get("seed", cfg.seed), path.name


def test_distributed_two_cpu_processes_stay_in_sync(tiny_dataset, tmp_path):
    # the documented launch from any folder: torchrun -m relightnet train (-m train works from the repository root)
    cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc_per_node=2", "-m", "relightnet",
           "train", "--config", str(REPO / "train" / "configs" / "tiny.yaml"), "--data", str(tiny_dataset),
           "--out", str(tmp_path / "ddp")]
    env = {**os.environ, "OMP_NUM_THREADS": "1", "PYTHONPATH": str(REPO)}
    r = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stderr.count("ranks in sync: 2 replicas") == 2
    assert load_checkpoint(tmp_path / "ddp" / "last.pt")["step"] == 6


def test_init_from_a_checkpoint_fine_tunes_it(tiny_dataset, tmp_path):
    base = TrainConfig(steps=1, batch_size=2, warmup=1, net=NET, threads=1)
    train(base, tiny_dataset, tmp_path / "a")
    start = load_model(tmp_path / "a" / "last.pt").state_dict()
    tune = TrainConfig(steps=1, batch_size=2, warmup=1, lr=1e-9, weight_decay=0.0, net=NET, threads=1,
                       init=str(tmp_path / "a" / "last.pt"))
    train(tune, tiny_dataset, tmp_path / "b")
    after = load_model(tmp_path / "b" / "last.pt").state_dict()
    for k, v in start.items():
        torch.testing.assert_close(after[k], v, atol=1e-6, rtol=0)
    other = TrainConfig(steps=1, batch_size=2, warmup=1, net={**NET, "width": 16}, init=str(tmp_path / "a" / "last.pt"))
    with pytest.raises(InputError, match="network configuration differs"):
        train(other, tiny_dataset, tmp_path / "c")


def test_render_target_model_aims_the_rendering_terms_at_the_learned_transport():
    g = torch.Generator().manual_seed(0)
    B, K, H, W = 2, 9, 8, 8
    A = torch.rand(B, 3, H, W, generator=g)
    Tu = torch.rand(B, K, H, W, generator=g)
    L = torch.rand(B, K, 3, generator=g)
    occluded = A * shading_map(0.6 * Tu, L)  # the photo: darker than A*(Tu.L) where occluded
    batch = {"image": occluded, "mask": torch.ones(B, 1, H, W), "albedo": A, "transport": Tu, "light": L}
    pred = Prediction(albedo=A, transport=Tu, light=L, mask=None)  # a perfect "occlusion ignored" net
    photo = relight_losses(pred, batch)
    model = relight_losses(pred, {**batch, "render": A * shading_map(Tu, L)})
    for k in ("render_al", "render_a", "render_tl"):
        assert photo[k] > 0.05 and float(model[k]) < 1e-6
    for k in ("transport", "albedo", "light", "shading_tl"):
        assert float(model[k]) == float(photo[k]) == 0.0


def test_novel_light_relighting_term():
    from relightnet.model.losses import LossWeights

    g = torch.Generator().manual_seed(1)
    B, K, H, W = 3, 9, 8, 8
    A, T = torch.rand(B, 3, H, W, generator=g), torch.rand(B, K, H, W, generator=g)
    L = torch.rand(B, K, 3, generator=g)
    batch = {"image": A * shading_map(T, L), "mask": torch.ones(B, 1, H, W), "albedo": A, "transport": T, "light": L}
    on = LossWeights(relit_novel=1.0)
    assert "relit_novel" not in relight_losses(Prediction(A, T, L), batch)  # off by default
    assert float(relight_losses(Prediction(A, T, L), batch, on)["relit_novel"]) < 1e-7  # the truth relights exactly
    # Albedo that absorbed the shading of its own light reproduces the photo but not another light.
    baked = A * shading_map(T, L) / shading_map(T, L).mean((2, 3), keepdim=True)
    flat = torch.ones_like(T) * T.mean((2, 3), keepdim=True)
    terms = relight_losses(Prediction(baked, flat, L), batch, on)
    expected = (baked * shading_map(flat, L.roll(1, 0)) - A * shading_map(T, L.roll(1, 0))).abs().mean()
    torch.testing.assert_close(terms["relit_novel"], expected)
    assert float(terms["relit_novel"]) > 0.01


def test_side_lights_and_the_round_trip_train_and_resume_bit_identically(tiny_dataset, tmp_path, monkeypatch):
    """novel_light "side" feeds relit_novel the drawn lights (seeded by the step); round_trip adds a
    second pass, logged as its own term and counted in the total."""
    from relightnet.model.losses import LossWeights

    cfg = TrainConfig(steps=3, batch_size=2, warmup=1, log_every=1, checkpoint_every=10, net=NET, threads=1,
                      novel_light="side", loss={"relit_novel": 1.0, "round_trip": 1.0})
    train(cfg, tiny_dataset, tmp_path / "full")
    train(cfg, tiny_dataset, tmp_path / "cut", stop_after=1)
    train(cfg, tiny_dataset, tmp_path / "cut", resume=True)
    full, cut = _losses(tmp_path / "full"), _losses(tmp_path / "cut")
    assert [(r["total"], r["round_trip"]) for r in full] == [(r["total"], r["round_trip"]) for r in cut]
    assert all(0 < r["round_trip"] <= 1 for r in full)  # a scale-invariant light error
    w = LossWeights(**cfg.loss).to_dict()
    assert full[0]["total"] == pytest.approx(sum(w[k] * v for k, v in full[0].items() if w.get(k)), rel=1e-5)
    with pytest.raises(InputError, match="novel_light"):
        TrainConfig(novel_light="sun")
    monkeypatch.setenv("WORLD_SIZE", "2")  # under torchrun: refused before any process group starts
    with pytest.raises(InputError, match="round_trip"):
        train(cfg, tiny_dataset, tmp_path / "ddp")
    assert not (tmp_path / "ddp").exists()


def test_training_with_render_target_model_runs_on_unoccluded_transport(tiny_dataset, tmp_path):
    cfg = TrainConfig(steps=2, batch_size=2, warmup=1, log_every=1, net=NET, threads=1,
                      target="transport_unoccluded", render_target="model")
    last = train(cfg, tiny_dataset, tmp_path / "u")
    assert last["step"] == 2 and torch.isfinite(torch.tensor(last["total"]))
    assert load_checkpoint(tmp_path / "u" / "last.pt")["train_config"]["render_target"] == "model"


def test_training_data_subset_half_precision_and_bf16(tiny_dataset, tmp_path):
    """train_items keeps the first items; float16 storage gives float32 batches close to the stored data;
    a bf16-autocast hybrid network trains (its light solve stays float32)."""
    from relightnet.model.training import TrainData

    full = TrainData(tiny_dataset)
    half = TrainData(tiny_dataset, dtype=torch.float16, limit=4)
    assert len(full) == 6 and len(half) == 4 and half.tensors["image"].dtype == torch.float16
    b = half.batch(torch.tensor([0, 3]))
    assert b["image"].dtype == torch.float32
    assert torch.allclose(b["image"], full.tensors["image"][[0, 3]], rtol=1e-3, atol=1e-3)
    cfg = TrainConfig(steps=2, batch_size=2, log_every=1, checkpoint_every=2, train_items=4, data_dtype="float16",
                      precision="bf16", net={"width": 8, "max_width": 32, "light_hidden": 16, "light_mode": "hybrid"},
                      loss={"light_head": 1.0, "light_si": 1.0})
    last = train(cfg, tiny_dataset, tmp_path / "run")
    assert last["step"] == 2 and all(torch.isfinite(torch.tensor(v)) for v in last.values())
    assert load_model(tmp_path / "run" / "last.pt").config.light_mode == "hybrid"
    with pytest.raises(InputError, match="train_items"):
        TrainConfig(train_items=0)
    with pytest.raises(InputError, match="precision"):
        TrainConfig(precision="fp8")


def test_a_candidate_carries_a_run_over_to_a_fresh_machine(tiny_dataset, tmp_path):
    from relightnet.model.training import CANDIDATE_BYTES

    cfg = TrainConfig(steps=4, batch_size=2, warmup=1, log_every=1, checkpoint_every=2, net=NET, threads=1)
    cand = tmp_path / "checkpoints" / "cand.pt"
    cand.parent.mkdir()
    train(cfg, tiny_dataset, tmp_path / "first", stop_after=2, candidate=cand)
    state = load_checkpoint(cand)
    assert "optimizer" not in state and state["step"] == 2 and state["train_config"] == cfg.to_dict()
    manifest = json.loads((Path(tiny_dataset) / "manifest.json").read_text())
    assert state["data_recipe"] == manifest["config"]  # the data is regenerated from its recipe
    assert cand.stat().st_size <= CANDIDATE_BYTES
    # A fresh machine: no run folder, only the committed candidate.
    train(cfg, tiny_dataset, tmp_path / "fresh", resume_from=cand)
    steps = [r["step"] for r in _losses(tmp_path / "fresh")]
    assert steps == [3, 4] and load_checkpoint(tmp_path / "fresh" / "last.pt")["step"] == 4
    assert not list(cand.parent.glob("*.new"))  # written beside, then moved over the previous candidate
    full = TrainConfig(**{**cfg.to_dict(), "steps": 5})
    with pytest.raises(InputError, match="different training config"):
        train(full, tiny_dataset, tmp_path / "other", resume_from=cand)
