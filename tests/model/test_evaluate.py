import pytest
import torch

from relightnet.model import NetConfig, RelightNet, shading_map
from relightnet.model.evaluate import baseline_from_train, evaluate, format_ablation, format_table


class Oracle(torch.nn.Module):
    """Predicts the ground truth of the items it is shown (looked up by input), to check the metrics."""

    def __init__(self, items):
        super().__init__()
        self.items = items
        self.p = torch.nn.Parameter(torch.zeros(1))

    def forward(self, x):
        from relightnet.model.network import Prediction

        return Prediction(self.items["albedo"][: len(x)], self.items["transport"][: len(x)],
                          self.items["light"][: len(x)], None)


def test_metrics_and_baseline(tiny_dataset, tmp_path):
    torch.manual_seed(0)
    net = RelightNet(NetConfig(width=8, max_width=32, light_hidden=32)).eval()
    base = baseline_from_train(tiny_dataset)
    assert base["albedo"].shape == (3,) and base["transport"].shape == (9,) and base["light"].shape == (9, 3)
    # Streamed item by item, it equals the means over the split held in memory.
    from relightnet.model.training import TrainData

    d = TrainData(tiny_dataset, "train")
    m = d.tensors["mask"]
    torch.testing.assert_close(base["transport"], (d.tensors["transport"] * m).sum((0, 2, 3)) / m.sum())
    torch.testing.assert_close(base["albedo"], (d.tensors["albedo"] * m).sum((0, 2, 3)) / m.sum())
    torch.testing.assert_close(base["light"], d.tensors["light"].mean(0))
    r = evaluate(net, tiny_dataset, "test", baseline=base, sheet=tmp_path / "sheet.png")
    assert r["n"] == 3
    for who in ("model", "baseline"):
        for k in ("transport_rmse", "albedo_rmse", "light_rmse", "shading_rmse", "relit_rmse", "relit_psnr",
                  "relit_ssim"):
            assert k in r[who] and torch.isfinite(torch.tensor(r[who][k]))
    assert (tmp_path / "sheet.png").stat().st_size > 500
    assert "| relit_rmse |" in format_table(r)


def test_perfect_prediction_scores_zero_error(tiny_dataset):
    from relightnet.data import SynthDataset

    ds = SynthDataset(tiny_dataset, "test", fields=("albedo", "transport", "light"))
    items = {k: torch.stack([ds[i][k] for i in range(len(ds))]) for k in ("albedo", "transport", "light")}
    r = evaluate(Oracle(items), tiny_dataset, "test", batch=8)
    m = r["model"]
    assert m["transport_rmse"] == 0 and m["albedo_rmse"] == 0 and m["light_rmse"] == 0 and m["relit_rmse"] == 0
    assert m["relit_ssim"] > 0.999
    # ... and the relit truth really changes the light: shading differs between items.
    assert not torch.allclose(shading_map(items["transport"][:1], items["light"][0]),
                              shading_map(items["transport"][:1], items["light"][1]))


def test_occlusion_floor_is_the_oracle_that_ignores_occlusion(tiny_dataset):
    from relightnet.data import SynthDataset

    ds = SynthDataset(tiny_dataset, "test", fields=("albedo", "transport_unoccluded", "light"))
    items = {k: torch.stack([ds[i][k] for i in range(len(ds))]) for k in ("albedo", "transport_unoccluded", "light")}
    items["transport"] = items.pop("transport_unoccluded")
    r = evaluate(Oracle(items), tiny_dataset, "test", batch=8, floor=True)
    ignoring, floor = r["model"], r["occlusion_floor"]
    assert floor["relit_rmse_concave"] > floor["relit_rmse"] > 0  # occlusion matters, most in the creases
    for k in ("relit_rmse", "relit_rmse_concave"):
        assert abs(floor[k] - ignoring[k]) < 1e-6
    aware = {"relit_rmse": 0.08, "relit_rmse_concave": 0.06}
    table = format_ablation(aware, {"relit_rmse": 0.1, "relit_rmse_concave": 0.1}, floor)
    assert "| occlusion-aware lower by | 20.0% | 40.0% |" in table


def test_items_scored_as_photos_sit_on_the_framed_box(tiny_dataset, tmp_path):
    from relightnet.cli import main
    from relightnet.data import SynthDataset
    from relightnet.model.checkpoint import save_checkpoint
    from relightnet.model.photo_input import as_photo

    # An oracle of the framed truth scores zero: the truth is resampled onto the box the input shows.
    ds = SynthDataset(tiny_dataset, "test", fields=("image", "image_composite", "mask", "albedo", "transport", "light"))
    framed = [as_photo({k: v.float() for k, v in ds[i].items()}, True, 1.0, 0, 0.05)
              for i in range(len(ds))]
    items = {k: torch.stack([f[k] for f in framed]) for k in ("albedo", "transport", "light")}
    r = evaluate(Oracle(items), tiny_dataset, "test", batch=8, photo=True)
    assert r["as_photo"] and r["model"]["transport_rmse"] == 0 and r["model"]["relit_rmse"] == 0
    torch.manual_seed(0)
    net = RelightNet(NetConfig(width=8, max_width=32, light_hidden=32)).eval()
    ckpt = save_checkpoint(tmp_path / "m.pt", net, net.config, step=0, input_size=32)
    out = tmp_path / "rep"
    assert main(["evaluate", "data", "--checkpoint", str(ckpt), "--data", str(tiny_dataset), "--no-baseline",
                 "--as-photo", "--out", str(out)]) == 0
    assert "as photos" in (out / "report.md").read_text()
    with pytest.raises(SystemExit):  # the light report scores both framings: --as-photo is not among its options
        main(["evaluate", "light", "--as-photo", "--data", str(tiny_dataset), "--out", str(out)])
