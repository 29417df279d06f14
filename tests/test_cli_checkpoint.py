"""`relightnet convert-checkpoint` at the command line (the conversion itself: tests/model/test_checkpoint.py)."""

import torch

from relightnet.cli import main
from relightnet.model.checkpoint import load_checkpoint, save_checkpoint
from relightnet.model.network import NetConfig, RelightNet


def test_convert_into_a_new_folder_and_errors(tmp_path, capsys):
    cfg = NetConfig(width=4, max_width=8, levels=2, light_hidden=8)
    net = RelightNet(cfg)
    save_checkpoint(tmp_path / "ok.pt", net, cfg, input_size=32)
    assert main(["-q", "convert-checkpoint", str(tmp_path / "ok.pt"), str(tmp_path / "safe" / "ok.pt")]) == 0
    ck = load_checkpoint(tmp_path / "safe" / "ok.pt")
    assert all(torch.equal(ck["model"][k], v) for k, v in net.state_dict().items())
    assert main(["convert-checkpoint", str(tmp_path / "missing.pt"), str(tmp_path / "new" / "x.pt")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "missing.pt" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ok.pt", "safe"]
