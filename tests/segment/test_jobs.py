"""relightnet.segment.jobs: the segment job as a library call (the CLI only parses; test_cli_segment runs it)."""

from __future__ import annotations

import pytest

from relightnet.checks import InputError
from relightnet.io import read_mask, write_image
from relightnet.segment import segment_files


def test_segment_files_of_a_photo_writes_its_mask(astronaut, person_models, tmp_path):
    write_image(tmp_path / "a.png", astronaut.permute(1, 2, 0), srgb=False)
    res = segment_files(tmp_path / "a.png", tmp_path / "m.png", person_models, landmarks=tmp_path / "lm.npz")
    assert len(res) == 1 and res[0] is not None
    mask = read_mask(tmp_path / "m.png")
    assert mask.shape == astronaut.shape[1:] and mask.any() and (tmp_path / "lm.npz").is_file()


@pytest.mark.parametrize("src, out, match", [
    ("empty", "masks", "no photos"),
    ("empty", "masks.png", "no photos"),
    ("a.png", "m.mkv", "expected a .png path"),
    ("clip.mkv", "m.avi", "expected a mask video"),
])
def test_segment_files_refuses_outputs_of_the_wrong_kind(astronaut, person_models, tmp_path, src, out, match):
    (tmp_path / "empty").mkdir()
    write_image(tmp_path / "a.png", astronaut.permute(1, 2, 0), srgb=False)
    with pytest.raises(InputError, match=match):
        segment_files(tmp_path / src, tmp_path / out, person_models)
    assert not (tmp_path / out).exists()


def test_segment_files_reads_every_photo_type_and_names_what_it_skips(astronaut, person_models, tmp_path, caplog):
    from PIL import Image

    photos = tmp_path / "photos"
    photos.mkdir()
    img = (astronaut.permute(1, 2, 0).clamp(0, 1) * 255).round().byte().numpy()
    Image.fromarray(img).save(photos / "a.webp", quality=95)
    (photos / "notes.txt").write_text("not a photo")
    res = segment_files(photos / "a.webp", tmp_path / "m.png", person_models)
    assert len(res) == 1 and read_mask(tmp_path / "m.png").any()
    with caplog.at_level("WARNING", logger="relightnet.segment"):
        res = segment_files(photos, tmp_path / "masks", person_models)
    assert len(res) == 1 and (tmp_path / "masks").is_dir()
    assert "1 file(s) that are not photos skipped (notes.txt)" in caplog.text


def _lying_mp4(path, n: int = 6):
    """An n-frame mp4 whose ``stts`` claims 20 million frames."""
    import struct

    import numpy as np

    from relightnet.io import VideoWriter

    with VideoWriter(path, fps=10) as w:
        for _ in range(n):
            f = np.full((64, 64, 3), 80, np.uint8)
            f[16:48, 20:44] = 200
            w.write(f)
    data = bytearray(path.read_bytes())
    at = data.find(b"stts")
    data[at + 12:at + 16] = struct.pack(">I", 20_000_000)
    path.write_bytes(bytes(data))
    return path


def test_progress_total_is_the_frames_really_in_the_file(person_models, tmp_path, capsys):
    from relightnet.io import video_info
    from relightnet.segment.sources import video_masks

    video = _lying_mp4(tmp_path / "lie.mp4")
    assert video_info(video).n_frames == 20_000_000  # what the header claims
    with pytest.raises(InputError, match="no person found in any frame"):  # the bar ran over every frame first
        segment_files(video, tmp_path / "m.mkv", person_models, allow_empty=True, progress=True)
    err = capsys.readouterr().err
    assert "6/6" in err and "20000000" not in err
    assert video_masks(video, source="head")[1] == 6
