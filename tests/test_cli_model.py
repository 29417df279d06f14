import json
from pathlib import Path

import numpy as np
import pytest
import torch

from relightnet.cli import main
from relightnet.io import write_image
from relightnet.light import load_light

pytestmark = pytest.mark.slow  # train and evaluate through the CLI

REPO = Path(__file__).resolve().parents[1]


def test_train_evaluate_estimate_light(tiny_dataset, tmp_path, capsys):
    run = tmp_path / "run"
    assert main(["-q", "train", "--config", str(REPO / "train/configs/tiny.yaml"), "--data", str(tiny_dataset),
                 "--out", str(run)]) == 0
    ckpt = run / "last.pt"
    assert ckpt.is_file() and (run / "metrics.jsonl").is_file()
    assert main(["-q", "evaluate", "data", "--checkpoint", str(ckpt), "--data", str(tiny_dataset),
                 "--out", str(tmp_path / "rep")]) == 0
    metrics = json.loads((tmp_path / "rep" / "metrics.json").read_text())
    assert metrics["n"] == 3 and "relit_rmse" in metrics["model"]
    assert "| metric |" in (tmp_path / "rep" / "report.md").read_text()
    assert main(["-q", "evaluate", "data", "--checkpoint", str(ckpt), "--ablation", str(ckpt), "--no-baseline",
                 "--data", str(tiny_dataset), "--out", str(tmp_path / "abl")]) == 0
    metrics = json.loads((tmp_path / "abl" / "metrics.json").read_text())
    assert metrics["ablation"] == metrics["model"]  # the same checkpoint twice
    assert metrics["occlusion_floor"]["relit_rmse_concave"] > 0
    assert "| occlusion-aware lower by | 0.0% | 0.0% |" in (tmp_path / "abl" / "report.md").read_text()
    # A photo-like input of any size with a mask.
    img = np.zeros((90, 70, 3), np.uint8)
    img[10:80, 20:50] = 180
    mask = np.zeros((90, 70, 3), np.uint8)
    mask[10:80, 20:50] = 255
    write_image(tmp_path / "p.png", img)
    write_image(tmp_path / "m.png", mask)
    for out in ("l.npz", "l.npy"):
        assert main(["-q", "estimate-light", str(tmp_path / "p.png"), "--mask", str(tmp_path / "m.png"),
                     "--checkpoint", str(ckpt), "--size", "32", "--out", str(tmp_path / out)]) == 0
    a, b = load_light(tmp_path / "l.npz"), load_light(tmp_path / "l.npy")
    assert a.shape == (9, 3) and torch.allclose(a, b, atol=1e-5)


def test_bad_inputs(tmp_path, tiny_dataset, capsys):
    assert main(["train", "--config", str(REPO / "train/configs/tiny.yaml"), "--data", str(tmp_path),
                 "--out", str(tmp_path / "r")]) == 1
    assert "no manifest.json" in capsys.readouterr().err
    (tmp_path / "junk.pt").write_bytes(b"junk")
    assert main(["evaluate", "data", "--checkpoint", str(tmp_path / "junk.pt"), "--data", str(tiny_dataset),
                 "--out", str(tmp_path / "e")]) == 1
    assert "unreadable checkpoint" in capsys.readouterr().err
    write_image(tmp_path / "p.png", np.zeros((8, 8, 3), np.uint8))
    write_image(tmp_path / "m.png", np.zeros((9, 8, 3), np.uint8))
    assert main(["estimate-light", str(tmp_path / "p.png"), "--mask", str(tmp_path / "m.png"),
                 "--checkpoint", str(tmp_path / "junk.pt"), "--out", str(tmp_path / "l.npz")]) == 1
    assert "differs from the image" in capsys.readouterr().err
    assert not (tmp_path / "l.npz").exists()
    write_image(tmp_path / "m.png", np.full((8, 8, 3), 255, np.uint8))
    assert main(["estimate-light", str(tmp_path / "p.png"), "--mask", str(tmp_path / "m.png"), "--device", "tpu",
                 "--out", str(tmp_path / "l.npz")]) == 1
    assert "device tpu: expected cpu or cuda" in capsys.readouterr().err
    if not torch.cuda.is_available():  # the message a GPU-less machine gives, not "unreadable checkpoint"
        assert main(["estimate-light", str(tmp_path / "p.png"), "--device", "cuda", "--mask-source", "head",
                     "--out", str(tmp_path / "l.npz")]) == 1
        assert "CUDA is not available" in capsys.readouterr().err
    for size in ("0", "-16", "100000"):
        with pytest.raises(SystemExit):
            main(["estimate-light", str(tmp_path / "p.png"), "--size", size, "--out", str(tmp_path / "l.npz")])
        assert "multiple of 16 from 16 to 2048" in capsys.readouterr().err
    assert not (tmp_path / "l.npz").exists()


def test_estimate_light_of_a_plate_and_of_both(tmp_path, capsys):
    from relightnet.light import combine_person_plate, load_plate
    from relightnet.light.plate import load_plate_light

    g = np.random.default_rng(0)
    plate = np.concatenate([np.full((30, 80, 3), 220), np.full((30, 80, 3), 40)]).astype(np.uint8)
    plate = (plate + g.integers(0, 20, plate.shape)).astype(np.uint8)  # a bright sky over a dark ground
    write_image(tmp_path / "plate.png", plate)
    assert main(["-q", "estimate-light", "--plate", str(tmp_path / "plate.png"), "--fov", "50",
                 "--out", str(tmp_path / "plate.npz")]) == 0
    on_plate = load_light(tmp_path / "plate.npz")
    torch.testing.assert_close(on_plate, load_plate_light(tmp_path / "plate.png", hfov_deg=50.0))
    assert float(on_plate[2, 0]) > 0  # more light from above
    img = np.full((90, 70, 3), 60, np.uint8)
    img[10:80, 20:50] = 180
    mask = np.zeros((90, 70, 3), np.uint8)
    mask[10:80, 20:50] = 255
    write_image(tmp_path / "p.png", img)
    write_image(tmp_path / "m.png", mask)
    photo = ["-q", "estimate-light", str(tmp_path / "p.png"), "--mask", str(tmp_path / "m.png")]
    assert main([*photo, "--out", str(tmp_path / "person.npz")]) == 0
    assert main([*photo, "--plate", str(tmp_path / "plate.png"), "--fov", "50", "--out", str(tmp_path / "b.npz")]) == 0
    torch.testing.assert_close(load_light(tmp_path / "b.npz"),
                               combine_person_plate(load_light(tmp_path / "person.npz"),
                                                    *load_plate(tmp_path / "plate.png", hfov_deg=50.0)))
    capsys.readouterr()
    assert main(["estimate-light", "--out", str(tmp_path / "x.npz")]) == 1
    assert "give a photo of a person (IMAGE), a background plate (--plate), or both" in capsys.readouterr().err
    assert main([*photo[1:], "--fov", "50", "--out", str(tmp_path / "x.npz")]) == 1
    assert "--fov is the plate's field of view" in capsys.readouterr().err
    assert not (tmp_path / "x.npz").exists()


def test_evaluate_fit_writes_its_report(tmp_path, capsys):
    out = tmp_path / "fit"
    assert main(["evaluate", "fit", "--clips", "1", "--frames", "2", "--res", "128", "--out", str(out)]) == 0
    metrics = json.loads((out / "fit_metrics.json").read_text())
    assert metrics["frames"] == 2 and len(metrics["clips"]) == 1 and metrics["median"]["mpjpe"] > 0
    assert "| mpjpe |" in capsys.readouterr().out and "| iou_body |" in (out / "fit_report.md").read_text()
    with pytest.raises(SystemExit):
        main(["evaluate", "fit", "--data", str(tmp_path), "--out", str(tmp_path / "x")])
    assert "unrecognized arguments: --data" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
