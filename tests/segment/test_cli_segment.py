"""``relightnet segment``: a photo, a folder of photos, a video; landmarks; one-line errors."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from people import background, iou

from relightnet.cli import main
from relightnet.io import VideoWriter, read_mask, write_image
from relightnet.io.video_masks import read_masks

pytestmark = pytest.mark.slow  # segmentation of photos and a video through the CLI


def test_segment_photo_folder_and_video(person_scene, walking_clip, tmp_path, capsys):
    img, truth = person_scene
    write_image(tmp_path / "person.png", img.permute(1, 2, 0), srgb=False)
    assert main(["-q", "segment", str(tmp_path / "person.png"), "--out", str(tmp_path / "mask.png"),
                 "--landmarks", str(tmp_path / "lm.npz")]) == 0
    assert iou(read_mask(tmp_path / "mask.png"), truth) > 0.9
    lm = np.load(tmp_path / "lm.npz")
    assert lm["landmarks"].shape == (1, 33, 5) and lm["world"].shape == (1, 33, 3) and lm["found"].all()
    assert str(lm["names"][0]) == "nose"

    photos = tmp_path / "photos"
    photos.mkdir()
    write_image(photos / "a.png", img.permute(1, 2, 0), srgb=False)
    write_image(photos / "b.png", background("chelsea", (120, 160)).permute(1, 2, 0), srgb=False)  # no person
    assert main(["segment", str(photos), "--out", str(tmp_path / "masks")]) == 1
    assert "b.png: no person found" in capsys.readouterr().err
    assert not (tmp_path / "masks").exists() and not list(tmp_path.glob(".masks*"))  # nothing half-written
    assert main(["-q", "segment", str(photos), "--out", str(tmp_path / "masks"), "--allow-empty"]) == 0
    assert sorted(p.name for p in (tmp_path / "masks").iterdir()) == ["a.png", "b.png"]
    assert not read_mask(tmp_path / "masks" / "b.png").any()

    frames, masks = walking_clip
    with VideoWriter(tmp_path / "walk.mkv", fps=10) as w:
        for f in frames:
            w.write((f.permute(1, 2, 0) * 255).round().to(torch.uint8).numpy())
    assert main(["-q", "segment", str(tmp_path / "walk.mkv"), "--out", str(tmp_path / "walk_masks.mkv"),
                 "--landmarks", str(tmp_path / "walk.npz")]) == 0
    n, got = read_masks(tmp_path / "walk_masks.mkv")
    assert n == len(frames) and all(iou(m, t) > 0.85 for m, t in zip(got, masks, strict=True))
    assert np.load(tmp_path / "walk.npz")["landmarks"].shape == (len(frames), 33, 5)


def test_segment_errors(tmp_path, capsys):
    assert main(["segment", str(tmp_path / "nope.png"), "--out", str(tmp_path / "m.png")]) == 1
    assert "nope.png: not found" in capsys.readouterr().err
    write_image(tmp_path / "cat.png", background("chelsea", (120, 160)).permute(1, 2, 0), srgb=False)
    assert main(["segment", str(tmp_path / "cat.png"), "--out", str(tmp_path / "m.png")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cat.png: no person found" in err and not (tmp_path / "m.png").exists()
    assert main(["segment", str(tmp_path / "cat.png"), "--out", str(tmp_path / "m.jpg")]) == 1
    assert "expected a .png path" in capsys.readouterr().err


def test_segment_steady_option(tmp_path, capsys):
    from relightnet.cli import build_parser
    from relightnet.segment.steady import STEADY_MARGIN

    write_image(tmp_path / "cat.png", background("chelsea", (120, 160)).permute(1, 2, 0), srgb=False)
    assert main(["segment", str(tmp_path / "cat.png"), "--out", str(tmp_path / "m.png"), "--steady", "0.5"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--steady: expected a probability margin in [0, 0.5), got 0.5" in err
    args = build_parser().parse_args(["segment", "clip.mp4", "--out", "m.mkv"])
    assert args.steady == STEADY_MARGIN  # the help's default is the library's


def test_segment_soft_writes_a_gray_matte(person_scene, walking_clip, tmp_path, capsys):
    from PIL import Image

    img, truth = person_scene
    write_image(tmp_path / "person.png", img.permute(1, 2, 0), srgb=False)
    assert main(["-q", "segment", str(tmp_path / "person.png"), "--soft", "--out", str(tmp_path / "alpha.png")]) == 0
    with Image.open(tmp_path / "alpha.png") as im:
        assert im.mode == "L"
        alpha = np.asarray(im)
    assert alpha.shape == tuple(truth.shape) and ((alpha > 0) & (alpha < 255)).any()  # fractional edge pixels
    assert iou(torch.from_numpy(alpha > 127), truth) > 0.9
    frames, _ = walking_clip
    with VideoWriter(tmp_path / "walk.mkv", fps=10) as w:
        for f in frames:
            w.write((f.permute(1, 2, 0) * 255).round().to(torch.uint8).numpy())
    assert main(["segment", str(tmp_path / "walk.mkv"), "--soft", "--out", str(tmp_path / "m.mkv")]) == 1
    assert "--soft" in capsys.readouterr().err and not (tmp_path / "m.mkv").exists()
