import json
import shutil

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.cli import main
from relightnet.io import read_image, read_video, video_info
from relightnet.model import NetConfig, RelightNet, save_checkpoint
from relightnet.pipeline import PredictorSettings
from relightnet.pipeline.compare import compare
from relightnet.prt import PrtSettings

pytestmark = pytest.mark.slow  # whole 2D-vs-3D comparisons on generated clips (CNN, PRT, renders), 1-2 min each

T = 3
RES = 32


def _no_leftovers(parent, name):
    return not (parent / name).exists() and not list(parent.glob(f".{name}.*"))


def test_command_writes_the_report(seq_dir, tmp_path):
    out = tmp_path / "report"
    assert main(["-q", "compare", "--data", str(seq_dir), "--out", str(out), "--n-dirs", "16"]) == 0
    text = (out / "report.md").read_text()
    assert "| 3D | smoothed L̃_t |" in text and "| 2D | true L_t |" in text and "relightnet_small.pt" in text
    m = json.loads((out / "metrics.json").read_text(), parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))
    assert len(m["summary"]["rows"]) == 6 and m["settings"]["clips"] == [0, 1] and len(m["clips"]) == 2
    assert m["settings"]["albedo_2d"] == "photo" and "the photo's albedo" in text
    for c in m["clips"]:
        assert len(c["rows"]) == 6 and all(len(r["per_frame"]["ssim"]) == T for r in c["rows"])
        assert c["mask_iou_3d"] == 1.0 and len(c["light"]["raw"]["per_frame"]) == T
    for r in m["summary"]["rows"]:
        assert 0 < r["rmse"] < 0.5 and 0 < r["ssim"] <= 1 and r["temporal"] >= 0
    for name in ("errors", "light_error", "clip00000_errors", "clip00000_light", "clip00001_light"):
        assert read_image(out / "plots" / f"{name}.png").shape[-1] == 3
    info = video_info(out / "side_by_side.mp4")
    frames = list(read_video(out / "side_by_side.mp4"))
    assert len(frames) == 2 * T and frames[0].shape == (RES, 4 * RES, 3) and info.size == (RES, 4 * RES)
    lights = np.load(out / "lights.npz")
    assert lights["clip1_smoothed"].shape == (T, 9, 3) and lights["clip0_outliers"].dtype == bool
    assert not list(tmp_path.glob(".report.*"))  # the staging folder is gone

    # Another checkpoint (a fresh tiny network) at another working size, one clip, no smoothing: same files.
    ckpt = tmp_path / "tiny.pt"
    cfg = NetConfig(width=8, max_width=16, levels=2, light_hidden=16)
    save_checkpoint(ckpt, RelightNet(cfg).eval(), cfg)
    assert main(["-q", "compare", "--data", str(seq_dir), "--out", str(out), "--n-dirs", "8", "--checkpoint",
                 str(ckpt), "--clips", "1", "--smoothing", "none", "--size", "32"]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert m["settings"]["clips"] == [0] and m["settings"]["checkpoint"] == str(ckpt)
    assert m["settings"]["size"] == 32 and m["settings"]["smoothing"] == "none"
    assert len(list(read_video(out / "side_by_side.mp4"))) == T
    assert not (out / "plots" / "clip00001_light.png").exists()  # the earlier run's clip plots are dropped


def test_bad_inputs_write_nothing(seq_dir, tiny_dataset, tmp_path, capsys):
    out = tmp_path / "rep"

    def fails(args, words):
        assert main(["compare", "--out", str(out), "--n-dirs", "8", *args]) == 1
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and words in err, err
        assert _no_leftovers(tmp_path, "rep")

    fails(["--data", str(tmp_path / "nope")], "nope: not found (expected a dataset folder of clips")
    fails(["--data", str(tiny_dataset)], "still samples")
    fails(["--data", str(seq_dir), "--split", "val"], "has no clips")
    bad = tmp_path / "bad.pt"
    bad.write_text("not a checkpoint")
    fails(["--data", str(seq_dir), "--checkpoint", str(bad)], "unreadable checkpoint")
    fails(["--data", str(seq_dir), "--checkpoint", str(tmp_path / "missing.pt")], "checkpoint not found")
    fails(["--data", str(seq_dir), "--source-light", "moon"], "preset")
    with pytest.raises(SystemExit):  # refused by the option parser, before anything runs
        main(["compare", "--out", str(out), "--data", str(seq_dir), "--size", "40"])
    assert "multiple of 16" in capsys.readouterr().err and _no_leftovers(tmp_path, "rep")
    out.write_text("a file")
    assert main(["compare", "--data", str(seq_dir), "--out", str(out)]) == 1
    assert "rep: is a file; expected a folder" in capsys.readouterr().err and out.read_text() == "a file"
    out.unlink()
    with pytest.raises(InputError, match="smoothing"):
        compare(seq_dir, out, smoothing="kalman")
    with pytest.raises(InputError, match="n_dirs"):
        compare(seq_dir, out, prt=PrtSettings(n_dirs=0))
    assert _no_leftovers(tmp_path, "rep")


def test_failure_mid_run_leaves_nothing(seq_dir, tmp_path, anny_body):
    # The second clip's shard is corrupt: the first clip is done by then, yet nothing may remain.
    data = tmp_path / "clips"
    shutil.copytree(seq_dir, data)
    (data / "test-00001.npz").write_bytes(b"PK\x03\x04 truncated")
    out = tmp_path / "deep" / "rep"
    with pytest.raises(InputError, match="test-00001.npz"):
        compare(data, out, prt=PrtSettings(n_dirs=8), progress=False, body=anny_body)
    assert not (tmp_path / "deep").exists() and not list(tmp_path.glob(".rep.*"))


def test_onnx_backend_matches_torch(seq_dir, tmp_path, anny_body):
    from relightnet.model.onnx_export import export_onnx

    torch.manual_seed(0)
    cfg = NetConfig(width=8, max_width=16, levels=2, light_hidden=16)
    net = RelightNet(cfg).eval()
    save_checkpoint(tmp_path / "tiny.pt", net, cfg)
    export_onnx(net, tmp_path / "tiny.onnx", smoothing="none", example_size=32)
    kw = dict(clips=1, prt=PrtSettings(n_dirs=8), progress=False, body=anny_body)
    a = compare(seq_dir, tmp_path / "torch", PredictorSettings(checkpoint=tmp_path / "tiny.pt", size=32), **kw).metrics
    onnx = PredictorSettings(checkpoint=tmp_path / "tiny.onnx", backend="onnx", size=32)
    b = compare(seq_dir, tmp_path / "onnx", onnx, **kw).metrics
    assert b["settings"]["backend"] == "onnx" and b["settings"]["size"] == 32
    la, lb = a["clips"][0]["light"], b["clips"][0]["light"]
    assert lb["raw"]["per_frame"] == pytest.approx(la["raw"]["per_frame"], rel=1e-3, abs=1e-5)
    for ra, rb in zip(a["summary"]["rows"], b["summary"]["rows"], strict=True):
        assert rb["rmse"] == pytest.approx(ra["rmse"], rel=1e-3, abs=1e-5), (ra["path"], ra["light"])
    with pytest.raises(InputError, match="backend"):
        compare(seq_dir, tmp_path / "x", PredictorSettings(backend="tensorrt", size=32), **kw)
    with pytest.raises(InputError, match="needs --backend onnx"):
        compare(seq_dir, tmp_path / "x", PredictorSettings(checkpoint=tmp_path / "tiny.onnx", size=32), **kw)
    assert _no_leftovers(tmp_path, "x")


def test_killed_compare_leaves_no_staging_folder_after_a_rerun(seq_dir, tmp_path, kill_mid_run):
    from .conftest import temp_files

    out = tmp_path / "report"
    argv = ["compare", "--data", str(seq_dir), "--out", str(out), "--n-dirs", "8"]
    # SIGKILL once the report is being staged (its staging folder holds a file).
    left = kill_mid_run(argv, tmp_path, ready=lambda temps: any(p.is_dir() and any(p.rglob("*")) for p in temps))
    assert left and not (out / "metrics.json").exists()
    assert main(["-q", *argv]) == 0
    assert temp_files(tmp_path) == [] and len(json.loads((out / "metrics.json").read_text())["clips"]) == 2
