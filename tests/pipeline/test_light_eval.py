"""evaluate light: per-family still metrics and drift/lag on generated clips (real generator, tiny sizes)."""

import json

import pytest
import torch

from relightnet.model import NetConfig, RelightNet
from relightnet.pipeline.light_eval import clip_metrics, evaluate_light, format_light_report, still_metrics

pytestmark = pytest.mark.slow  # a generated clip dataset, then the CNN over every frame


@pytest.fixture(scope="module")
def tiny_clips(tmp_path_factory, anny_body):
    from relightnet.data import SynthConfig
    from relightnet.data.synth import run_synth

    out = tmp_path_factory.mktemp("clips")
    paths = []
    for kind in ("constant", "switch"):
        cfg = SynthConfig(seed=4, res=32, n_dirs=16, shard_size=2, counts={"test": 1}, sequence_frames=10,
                          clip_lights=kind)
        run_synth(out / kind, cfg, workers=0, progress=False, body=anny_body)
        paths.append(out / kind)
    return paths


def _net(mode):
    torch.manual_seed(0)
    return RelightNet(NetConfig(width=8, max_width=32, light_hidden=16, levels=2, light_mode=mode)).eval()


def test_still_metrics_group_by_source():
    true = torch.randn(6, 9, 3)
    res = still_metrics(true * 2, true, ["hdri", "hdri", "window", "window", "window", "preetham"])
    assert res["hdri"]["n"] == 2 and res["window"]["n"] == 3 and res["all"]["n"] == 6
    assert res["all"]["error"]["median"] < 1e-5  # exposure does not count
    assert res["all"]["ambient_error"]["median"] > 0


def test_clip_metrics_of_perfect_and_lagging_estimates():
    a, b = torch.randn(9, 3), torch.randn(9, 3)
    const = {"raw": a.expand(10, 9, 3), "smoothed": a.expand(10, 9, 3), "true": a.expand(10, 9, 3), "switch": None}
    seq = torch.stack([a] * 5 + [b] * 5)
    late = torch.stack([a] * 7 + [b] * 3)
    sw = {"raw": seq, "smoothed": late, "true": seq, "switch": 5}
    m = clip_metrics([const, sw])
    assert m["raw"]["drift_p90"] < 1e-6 and m["raw"]["lag_median"] == 0 and m["smoothed"]["lag_median"] == 2


def test_evaluate_light_end_to_end(tiny_dataset, tiny_clips):
    res = evaluate_light(_net("hybrid"), tiny_dataset, clips=tiny_clips)
    assert res["stills"]["all"]["n"] == 3
    assert 0 <= res["stills"]["all"]["error"]["median"] <= 1
    # the same items as photos: their composites framed around their masks by the package's own path
    assert res["stills_photo"]["all"]["n"] == 3 and 0 <= res["stills_photo"]["all"]["error"]["median"] <= 1
    assert res["stills_photo"]["all"]["error"]["median"] != res["stills"]["all"]["error"]["median"]
    assert res["clips"]["raw"]["clips_constant"] == 1 and res["clips"]["raw"]["clips_switch"] == 1
    # pooled over a second of frames, a constant light drifts much less than the per-frame estimate
    assert res["clips"]["smoothed"]["drift_p90"] < 0.5 * res["clips"]["raw"]["drift_p90"]
    text = format_light_report(res)
    assert text.count("| all | 3 |") == 2 and "as photos" in text and "drift" in text
    json.dumps(res)


def test_cli_evaluate_light(tiny_dataset, tmp_path):
    from relightnet.cli import main
    from relightnet.model.checkpoint import save_checkpoint

    net = _net("solve")
    ckpt = save_checkpoint(tmp_path / "m.pt", net, net.config, step=0, input_size=32)
    rc = main(["evaluate", "light", "--checkpoint", str(ckpt), "--data", str(tiny_dataset), "--out",
               str(tmp_path / "rep")])
    assert rc == 0
    assert "| all | 3 |" in (tmp_path / "rep" / "light_report.md").read_text()
    assert json.loads((tmp_path / "rep" / "light_metrics.json").read_text())["stills"]["all"]["n"] == 3
