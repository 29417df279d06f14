"""Phone media: EXIF orientation of photos, display rotation of videos, alpha-channel masks."""

import struct

import av
import numpy as np
import pytest
import torch

from relightnet._cli.inputs import read_photo
from relightnet.io import VideoWriter, read_image, read_mask, read_video, video_info
from relightnet.io.image import _encode, read_alpha
from relightnet.io.video_masks import read_masks


def _half_white(h=40, w=60):
    """Left half white, right half black: where the white half ends up tells the rotation."""
    img = np.zeros((h, w, 3), np.uint8)
    img[:, : w // 2] = 255
    return img


def _jpeg_with_orientation(path, img, orientation):
    """A JPEG whose EXIF block (big-endian TIFF, one IFD entry) carries ``orientation`` (1..8)."""
    frame = av.VideoFrame.from_ndarray(img, format="rgb24").reformat(format="yuvj444p")
    data = _encode("mjpeg", frame)
    tiff = b"MM\x00*" + struct.pack(">I", 8) + struct.pack(">H", 1)
    tiff += struct.pack(">HHIHH", 0x0112, 3, 1, orientation, 0) + struct.pack(">I", 0)
    app1 = b"Exif\x00\x00" + tiff
    segment = b"\xff\xe1" + struct.pack(">H", len(app1) + 2) + app1
    path.write_bytes(data[:2] + segment + data[2:])  # right after SOI
    return path


@pytest.mark.parametrize(("orientation", "corner"), [(1, "tl"), (2, "tr"), (3, "br"), (4, "bl"),
                                                   (5, "tl"), (6, "tr"), (7, "br"), (8, "bl")])
def test_exif_orientation_turns_photos_upright(tmp_path, orientation, corner):
    img = np.zeros((40, 60, 3), np.uint8)
    img[:20, :30] = 255  # the top-left quarter is white
    img = read_image(_jpeg_with_orientation(tmp_path / "p.jpg", img, orientation))
    assert img.shape == ((60, 40, 3) if orientation >= 5 else (40, 60, 3))
    g = img.mean(-1)
    h, w = g.shape
    quarters = {"tl": g[: h // 2, : w // 2], "tr": g[: h // 2, w // 2:], "bl": g[h // 2:, : w // 2],
                "br": g[h // 2:, w // 2:]}
    for name, q in quarters.items():
        assert (q.mean() > 0.9) if name == corner else (q.mean() < 0.1), (name, float(q.mean()))


def _png_rgba(path, rgba):
    path.write_bytes(_encode("png", av.VideoFrame.from_ndarray(rgba, format="rgba")))
    return path


def test_alpha_is_a_mask_and_opaque_images_have_none(tmp_path):
    rgba = np.full((20, 30, 4), 200, np.uint8)
    rgba[..., 3] = 0
    rgba[5:15, 10:20, 3] = 255  # the person
    path = _png_rgba(tmp_path / "cutout.png", rgba)
    assert read_image(path).shape == (20, 30, 3)
    alpha = read_alpha(path)
    assert alpha is not None and alpha.shape == (20, 30)
    torch.testing.assert_close(read_mask(path), torch.from_numpy(rgba[..., 3] > 127).float())
    # Opaque RGBA and plain RGB: no alpha; the mask is white = person.
    opaque = rgba.copy()
    opaque[..., 3] = 255
    opaque[..., :3] = 0
    opaque[2:6, 3:9, :3] = 255
    path = _png_rgba(tmp_path / "opaque.png", opaque)
    assert read_alpha(path) is None
    torch.testing.assert_close(read_mask(path), torch.from_numpy(opaque[..., 0] > 127).float())
    # A folder of cut-out masks is read the same way.
    d = tmp_path / "masks"
    d.mkdir()
    _png_rgba(d / "0.png", rgba)
    n, masks = read_masks(d)
    assert n == 1 and torch.equal(next(masks), read_mask(tmp_path / "cutout.png"))


def test_photo_commands_take_a_cutouts_alpha_as_the_mask(tmp_path):
    rgba = np.zeros((20, 30, 4), np.uint8)
    rgba[5:15, 10:20] = 255
    path = _png_rgba(tmp_path / "cutout.png", rgba)
    img, mask, alpha = read_photo(str(path), None)
    assert alpha is not None and torch.equal(mask, (alpha > 0.5).float())
    assert img.shape == (3, 20, 30) and mask is not None and int(mask.sum()) == 100
    plain = tmp_path / "plain.png"
    plain.write_bytes(_encode("png", av.VideoFrame.from_ndarray(rgba[..., :3].copy(), format="rgb24")))
    assert read_photo(str(plain), None, mask_source="head")[1] is None  # no alpha: the mask head's job
    empty = rgba.copy()
    empty[..., 3] = 0
    with pytest.raises(ValueError, match="alpha channel: empty mask"):
        read_photo(str(_png_rgba(tmp_path / "empty.png", empty)), None)
    with pytest.raises(ValueError, match="--mask .* differs"):
        read_photo(str(path), str(_png_rgba(tmp_path / "small.png", rgba[:10])))


def test_video_display_rotation_is_applied(tmp_path):
    path = tmp_path / "phone.mp4"
    with VideoWriter(path, fps=10) as w:
        for _ in range(3):
            w.write(_half_white(32, 64))
    # A phone stores portrait video sideways with a 90° display matrix in the track header:
    # write that matrix in place of the identity one.
    data = bytearray(path.read_bytes())
    identity = struct.pack(">9I", 0x10000, 0, 0, 0, 0x10000, 0, 0, 0, 0x40000000)
    at = data.rfind(identity)  # the track's (tkhd) matrix comes after the movie's (mvhd)
    assert at > data.find(identity) >= 0
    data[at:at + 36] = struct.pack(">9i", 0, 0x10000, 0, -0x10000, 0, 0, 0, 0, 0x40000000)
    path.write_bytes(bytes(data))
    assert video_info(path).size == (64, 32)
    frames = list(read_video(path))
    assert len(frames) == 3 and frames[0].shape == (64, 32, 3)
    g = frames[0].mean(-1)
    assert g[:32].mean() > 230 and g[32:].mean() < 25  # the white half is on top, as a viewer shows it


def test_write_image_with_alpha(tmp_path):
    from relightnet.checks import ShapeError
    from relightnet.io import write_image

    img = torch.rand(6, 5, 3)
    alpha = torch.zeros(6, 5)
    alpha[1:4, 2:] = 1
    path = write_image(tmp_path / "a.png", img, alpha=alpha)
    torch.testing.assert_close(read_alpha(path), alpha)
    torch.testing.assert_close(read_image(path, linear=True), img, atol=0.02, rtol=0)
    with pytest.raises(ShapeError, match="alpha"):
        write_image(tmp_path / "b.png", img, alpha=torch.ones(5, 6))
    assert not (tmp_path / "b.png").exists()
