"""Converting an older checkpoint (numpy values, config objects) to the safe form; refusals by name."""

import dataclasses

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.cli import main
from relightnet.model import RelightNet, load_checkpoint, load_model
from relightnet.model.checkpoint import FORMAT
from relightnet.model.convert import convert_checkpoint

from .conftest import TINY as CFG
from .conftest import Payload as _Payload


def _old(net, **extra):
    return {"format": "relightnet-ckpt-1", "net_config": CFG, "model": net.state_dict(), "step": np.int64(7), **extra}


def test_older_checkpoint_with_numpy_and_config_objects_converts(tmp_path, capsys):
    torch.manual_seed(0)
    net = RelightNet(CFG)
    old = _old(net, input_size=np.int32(32), stats=np.arange(3.0))
    torch.save(old, tmp_path / "old.pt")
    with pytest.raises(InputError, match="holds .*relightnet.model.network.NetConfig|holds numpy"):
        load_checkpoint(tmp_path / "old.pt")
    assert main(["-q", "convert-checkpoint", str(tmp_path / "old.pt"), str(tmp_path / "new.pt")]) == 0
    state = load_checkpoint(tmp_path / "new.pt")
    assert state["format"] == FORMAT and state["step"] == 7 and type(state["step"]) is int
    assert state["net_config"] == dataclasses.asdict(CFG) and torch.equal(state["stats"], torch.arange(3.0).double())
    m = load_model(tmp_path / "new.pt")
    assert m.config.input_size == 32 and all(torch.equal(a, b) for a, b in zip(m.state_dict().values(),
                                                                         net.state_dict().values(), strict=True))


def test_a_train_config_object_pickled_by_an_older_version_converts(tmp_path, monkeypatch):
    from relightnet.model.train_config import TrainConfig

    torch.manual_seed(0)
    net = RelightNet(CFG)
    old_cfg = TrainConfig(steps=3)
    for key, value in {"net": {"width": 4}, "loss": {}, "photo": {},  # sections were plain dicts then
                       "augment": {"flip": 0.5, "crop_scale": [0.875, 0.875]}}.items():
        object.__setattr__(old_cfg, key, value)
    with monkeypatch.context() as m:  # the class's module then: relightnet.model.training
        m.setattr(TrainConfig, "__module__", "relightnet.model.training")
        torch.save(_old(net, train_config=old_cfg), tmp_path / "old.pt")
    assert b"relightnet.model.training" in (tmp_path / "old.pt").read_bytes()
    convert_checkpoint(tmp_path / "old.pt", tmp_path / "new.pt")
    stored = load_checkpoint(tmp_path / "new.pt")["train_config"]
    assert stored["steps"] == 3 and stored["net"] == {"width": 4}
    assert TrainConfig.from_dict(stored) == TrainConfig(steps=3, net={"width": 4}, augment=stored["augment"])


def test_convert_in_place_with_nested_values(tmp_path):
    torch.manual_seed(0)
    net = RelightNet(CFG)
    old = _old(net, history={"loss": [np.float32(0.5), np.float64(0.25)], "shape": (np.int16(2), 3)},
               big_endian=np.arange(4, dtype=">f4"))
    path = tmp_path / "c.pt"
    torch.save(old, path)
    assert convert_checkpoint(path, path) == path  # dst may be src
    state = torch.load(path, weights_only=True)
    assert state["format"] == FORMAT and state["history"] == {"loss": [0.5, 0.25], "shape": (2, 3)}
    assert type(state["history"]["loss"][0]) is float and type(state["history"]["shape"][0]) is int
    assert state["big_endian"].dtype == torch.float32 and state["big_endian"].tolist() == [0.0, 1.0, 2.0, 3.0]
    assert all(torch.equal(state["model"][k], v) for k, v in net.state_dict().items())
    assert [p.name for p in tmp_path.iterdir()] == ["c.pt"]  # no temporary file left


def test_payload_is_refused_by_name_and_not_run(tmp_path):
    marker = tmp_path / "made"
    torch.save(_old(RelightNet(CFG), extra=_Payload(marker)), tmp_path / "evil.pt")
    with pytest.raises(InputError, match="refused: it holds posix.system"):
        convert_checkpoint(tmp_path / "evil.pt", tmp_path / "new.pt")
    assert not marker.exists() and not (tmp_path / "new.pt").exists()


def test_missing_unreadable_and_object_arrays_are_refused(tmp_path):
    with pytest.raises(InputError, match="none.pt: checkpoint not found"):
        convert_checkpoint(tmp_path / "none.pt", tmp_path / "new.pt")
    torch.save(_old(RelightNet(CFG), names=np.array(["a", None], dtype=object)), tmp_path / "obj.pt")
    (tmp_path / "cut.pt").write_bytes((tmp_path / "obj.pt").read_bytes()[:300])  # a truncated file
    with pytest.raises(InputError, match="cut.pt: unreadable checkpoint"):
        convert_checkpoint(tmp_path / "cut.pt", tmp_path / "new.pt")
    with pytest.raises(InputError, match="refused|object array"):
        convert_checkpoint(tmp_path / "obj.pt", tmp_path / "new.pt")
    assert not (tmp_path / "new.pt").exists()
