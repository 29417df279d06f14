"""Checkpoints: plain content only, weights_only loading, refusals by name, the shipped model."""

import dataclasses

import pytest
import torch

from relightnet.checks import InputError
from relightnet.model import RelightNet, load_model, save_checkpoint
from relightnet.model.checkpoint import FORMAT, SHIPPED

from .conftest import TINY as CFG
from .conftest import Payload as _Payload


def _state(**extra):
    torch.manual_seed(0)
    return {"format": FORMAT, "net_config": dataclasses.asdict(CFG), "model": RelightNet(CFG).state_dict(),
            "step": 1, **extra}


def test_save_and_load_plain_content(tmp_path):
    net = RelightNet(CFG)
    save_checkpoint(tmp_path / "c.pt", net, CFG, step=5, train_config={"lr": 1e-3, "net": {"width": 4}})
    state = torch.load(tmp_path / "c.pt", weights_only=True)  # what any reader can do safely
    assert state["format"] == FORMAT and state["step"] == 5
    m = load_model(tmp_path / "c.pt")
    assert all(torch.equal(a, b) for a, b in zip(m.state_dict().values(), net.state_dict().values(), strict=True))
    with pytest.raises(TypeError, match=r"checkpoint\['cfg'\] is a relightnet.model.network.NetConfig"):
        save_checkpoint(tmp_path / "d.pt", net, CFG, cfg=CFG)
    assert not (tmp_path / "d.pt").exists()


def test_payload_is_refused_by_name_and_not_run(tmp_path):
    marker = tmp_path / "made"
    torch.save(_state(extra=_Payload(marker)), tmp_path / "evil.pt")
    with pytest.raises(InputError, match=r"evil.pt: refused: the checkpoint holds posix.system .*convert-checkpoint"):
        load_model(tmp_path / "evil.pt")
    assert not marker.exists()


def test_bad_configurations_and_weights_allocate_nothing(tmp_path):
    def fails(state, text):
        torch.save(state, tmp_path / "x.pt")
        with pytest.raises(InputError, match=text):
            load_model(tmp_path / "x.pt")

    fails(_state(net_config={**dataclasses.asdict(CFG), "width": 10**9}), "outside")
    fails(_state(net_config={**dataclasses.asdict(CFG), "mask_head": "yes"}), "expected a bool")
    fails(_state(net_config={**dataclasses.asdict(CFG), "width": 64}), "weights do not match")
    bad = _state()
    bad["model"] = {k: v * float("nan") for k, v in bad["model"].items()}
    fails(bad, "NaN or Inf")
    fails(_state(step=-1), "'step'")
    fails(_state(input_size=10**9), "input_size")


def test_shipped_model_is_in_the_safe_form():
    state = torch.load(SHIPPED, weights_only=True)
    assert state["format"] == FORMAT and "optimizer" not in state
    load_model()


def test_architecture_and_storage_are_bounded(tmp_path):
    """A network over MAX_PARAMETERS (counted on the meta device), feature maps over MAX_ACTIVATION,
    stride-0 weights and shared "laughs" in plain values are refused in one line."""
    from relightnet.model.checkpoint import MAX_ACTIVATION, MAX_PARAMETERS, release_checkpoint

    def fails(state, text):
        torch.save(state, tmp_path / "x.pt")
        with pytest.raises(InputError, match=text) as e:
            load_model(tmp_path / "x.pt")
        assert len(str(e.value)) < 400
        return e.value

    wide = {**dataclasses.asdict(CFG), "width": 2048, "max_width": 4096}
    with torch.device("meta"):
        shapes = {k: v.shape for k, v in RelightNet(type(CFG)(**wide)).state_dict().items()}
    assert sum(s.numel() for s in shapes.values()) > MAX_PARAMETERS
    fails(_state(net_config=wide) | {"model": {k: torch.zeros(1).expand(s) for k, s in shapes.items()}},
          "M parameters; at most 64 M")
    assert 4096 ** 2 * 16 > MAX_ACTIVATION
    fails(_state(input_size=4096, net_config={**dataclasses.asdict(CFG), "width": 16, "max_width": 16}),
          "feature maps")
    state = _state()
    state["model"] = {k: v.reshape(-1)[:1].clone().expand(v.shape) if v.numel() > 1 else v
                      for k, v in state["model"].items()}
    fails(state, "stride 0")
    laugh: list = [1] * 9
    for _ in range(12):
        laugh = [laugh] * 9
    fails(_state(net_config={**dataclasses.asdict(CFG), "width": laugh}), "expected a int")
    torch.save(_state(train_config={"x": laugh}), tmp_path / "y.pt")
    with pytest.raises(TypeError, match="more than 100000 values"):
        release_checkpoint(tmp_path / "y.pt", tmp_path / "z.pt")


def test_pose_encoder_checkpoint_holds_only_what_trained(tmp_path):
    cfg = dataclasses.replace(CFG, encoder="pose", transport_head="cone")
    net = RelightNet(cfg)
    with torch.no_grad():
        for p in net.pose.proj.parameters():
            p.normal_()
    save_checkpoint(tmp_path / "c.pt", net, cfg, step=2)
    state = torch.load(tmp_path / "c.pt", weights_only=True)
    assert not any(k.startswith("pose.encoder.") for k in state["model"])  # frozen: the package's own file
    m = load_model(tmp_path / "c.pt").eval()
    x = torch.rand(1, 4, 32, 32)
    with torch.no_grad():
        torch.testing.assert_close(m(x).transport, net.eval()(x).transport)


def test_average_checkpoints_is_the_weighted_mean(tmp_path):
    """The weights are the weighted mean (in float64, stored in the sources' dtype); the file loads as a
    network; another network, an odd number of weights and a single source are refused in one line."""
    from relightnet.model.checkpoint import average_checkpoints

    a, b = _state(optimizer={"x": 1}), _state(step=7)
    b["model"] = {k: v + 1.0 if v.is_floating_point() else v for k, v in b["model"].items()}
    torch.save(a, tmp_path / "a.pt")
    torch.save(b, tmp_path / "b.pt")
    out = average_checkpoints([tmp_path / "a.pt", tmp_path / "b.pt"], tmp_path / "m.pt", weights=[3, 1])
    state = torch.load(out, weights_only=True)
    assert "optimizer" not in state and state["step"] == 7
    assert [d["weight"] for d in state["averaged_from"]] == [0.75, 0.25]
    for k, v in state["model"].items():
        if v.is_floating_point():
            torch.testing.assert_close(v, a["model"][k] + 0.25, rtol=0, atol=1e-6)
    load_model(out)
    # a checkpoint written before a configuration key existed (the key at its default) is the same network
    older = _state(net_config={k: v for k, v in dataclasses.asdict(CFG).items() if k != "work_scale"})
    torch.save(older, tmp_path / "older.pt")
    average_checkpoints([tmp_path / "older.pt", tmp_path / "b.pt"], tmp_path / "m2.pt")
    other = _state(net_config={**dataclasses.asdict(CFG), "width": 8})
    torch.save(other, tmp_path / "o.pt")
    for srcs, w, text in (([tmp_path / "a.pt", tmp_path / "o.pt"], None, "another network"),
                          ([tmp_path / "a.pt", tmp_path / "b.pt"], [1], "weights: expected 2"),
                          ([tmp_path / "a.pt"], None, "two or more")):
        with pytest.raises(InputError, match=text):
            average_checkpoints(srcs, tmp_path / "x.pt", weights=w)
    assert not (tmp_path / "x.pt").exists()
