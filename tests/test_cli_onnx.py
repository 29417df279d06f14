from pathlib import Path

import numpy as np
import pytest

from relightnet.cli import main
from relightnet.light import load_light
from relightnet.model.onnx_serving import OnnxRelighter

pytestmark = pytest.mark.slow  # export (dynamo) and onnx-run through the CLI

REPO = Path(__file__).resolve().parents[1]


def test_export_and_run_a_video(tiny_dataset, tmp_path, masked_clip, capsys):
    run = tmp_path / "run"
    assert main(["-q", "train", "--config", str(REPO / "train/configs/tiny.yaml"), "--data", str(tiny_dataset),
                 "--out", str(run)]) == 0
    onnx = tmp_path / "m.onnx"
    assert main(["-q", "export", "--checkpoint", str(run / "last.pt"), "--out", str(onnx),
                 "--smoothing", "one-euro"]) == 0
    assert OnnxRelighter(onnx).metadata["relightnet.smoothing"] == "one-euro"
    # --int8: a statically quantised copy calibrated on generated people at the model's size.
    q = tmp_path / "q.onnx"
    assert main(["-q", "export", "--checkpoint", str(run / "last.pt"), "--out", str(q), "--int8"]) == 0
    r8 = OnnxRelighter(tmp_path / "q_int8.onnx")
    img = np.random.default_rng(0).random((1, 3, 32, 32), dtype=np.float32)
    out8 = r8.step(img, np.ones((1, 1, 32, 32), np.float32))
    assert out8["albedo"].shape == (1, 3, 32, 32) and np.isfinite(out8["light_raw"]).all()
    video, masks = masked_clip(tmp_path, n=4, h=48, w=64)
    assert main(["-q", "onnx-run", str(onnx), "--video", str(video), "--masks", str(masks),
                 "--out-dir", str(tmp_path / "out"), "--size", "32"]) == 0
    raw, smooth = load_light(tmp_path / "out" / "lights_raw.npz"), load_light(tmp_path / "out" / "lights_smoothed.npz")
    assert raw.shape == (4, 9, 3) and smooth.shape == (4, 9, 3)
    assert (tmp_path / "out" / "albedo.mp4").is_file()
    # Too few masks: one clear error, nothing written.
    (masks / "003.png").unlink()
    assert main(["onnx-run", str(onnx), "--video", str(video), "--masks", str(masks),
                 "--out-dir", str(tmp_path / "out2")]) == 1
    assert not (tmp_path / "out2").exists()  # no empty folder left either
    # --out-dir naming a file; a bad --size; an export to a non-.onnx name.
    assert main(["onnx-run", str(onnx), "--video", str(video), "--masks", str(masks),
                 "--out-dir", str(onnx)]) == 1
    assert "is a file; expected a folder" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["onnx-run", str(onnx), "--video", str(video), "--masks", str(masks), "--out-dir",
              str(tmp_path / "o3"), "--size", "0"])
    assert "multiple of 16 from 16 to 2048" in capsys.readouterr().err
    assert main(["export", "--checkpoint", str(run / "last.pt"), "--out", str(tmp_path / "m.txt")]) == 1
    assert "expected a file ending in .onnx" in capsys.readouterr().err and not (tmp_path / "m.txt").exists()


def test_export_refuses_an_option_its_smoother_would_ignore(tmp_path, capsys):
    out = tmp_path / "m.onnx"
    assert main(["export", "--out", str(out), "--smoothing", "one-euro", "--alpha", "0.5"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--alpha: applies to --smoothing ema, not one-euro" in err[0], err
    assert list(tmp_path.iterdir()) == []
