"""sRGB transfer functions, PNG writing and reading; alpha only from files that have it."""

import av
import numpy as np
import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.color import linear_to_srgb, srgb_to_linear, srgb_to_linear_np
from relightnet.io import read_image, read_image_alpha, read_mask, to_uint8, write_image
from relightnet.io.image import read_alpha


def test_srgb_known_values_and_inverse():
    x = torch.tensor([0.0, 0.0031308, 0.18, 0.5, 1.0], dtype=torch.float64)
    y = linear_to_srgb(x)
    ref = torch.tensor([0.0, 0.0031308 * 12.92, 0.4613561295, 0.7353569831, 1.0], dtype=torch.float64)
    torch.testing.assert_close(y, ref, rtol=0, atol=1e-9)
    grid = torch.linspace(0, 1, 10001, dtype=torch.float64)
    torch.testing.assert_close(srgb_to_linear(linear_to_srgb(grid)), grid, rtol=0, atol=1e-12)
    torch.testing.assert_close(linear_to_srgb(srgb_to_linear(grid)), grid, rtol=0, atol=1e-12)
    # Both pieces meet (continuity at the breakpoints) and the curve is increasing.
    assert (linear_to_srgb(grid).diff() > 0).all()


def test_uint8_png_round_trip_is_exact(tmp_path):
    g = torch.Generator().manual_seed(0)
    img = torch.randint(0, 256, (7, 11, 3), generator=g, dtype=torch.uint8)
    path = write_image(tmp_path / "a.png", img)
    back = read_image(path)
    assert back.shape == (7, 11, 3) and back.dtype == torch.float32
    torch.testing.assert_close((back * 255).round().to(torch.uint8), img, rtol=0, atol=0)


def test_float_linear_is_srgb_encoded_and_read_back_linear(tmp_path):
    img = torch.linspace(0, 1, 64).reshape(4, 16, 1).expand(4, 16, 3).contiguous()
    path = write_image(tmp_path / "f.png", img)
    enc = read_image(path)
    torch.testing.assert_close(enc, linear_to_srgb(img), rtol=0, atol=0.5 / 255 + 1e-6)
    lin = read_image(path, linear=True)
    torch.testing.assert_close(lin, img, rtol=0, atol=0.01)
    raw = write_image(tmp_path / "raw.png", img, srgb=False)
    torch.testing.assert_close(read_image(raw), img, rtol=0, atol=0.5 / 255 + 1e-6)


def test_png_pixels_do_not_depend_on_the_compression_settings(tmp_path):
    """The fast PNG settings change the file's compression only: the pixels are FFmpeg's defaults'."""
    from relightnet.io.image import PNG_OPTIONS, _encode

    g = torch.Generator().manual_seed(1)
    img = (torch.rand(64, 96, 3, generator=g) * torch.linspace(0, 1, 96)[:, None]).mul(255).round().to(torch.uint8)
    ours = write_image(tmp_path / "fast.png", img)
    default = tmp_path / "default.png"
    default.write_bytes(_encode("png", av.VideoFrame.from_ndarray(img.numpy(), format="rgb24")))
    assert PNG_OPTIONS and ours.read_bytes() != default.read_bytes()
    assert torch.equal(read_image(ours), read_image(default))


@pytest.mark.parametrize("suffix", [".jpg", ".jpeg", ".webp"])
def test_lossy_outputs_keep_the_picture_and_the_profile(tmp_path, suffix):
    from PIL import Image

    from relightnet.io.icc import read_icc

    from .icc_profiles import display_p3

    y, x = torch.meshgrid(torch.linspace(0, 1, 48), torch.linspace(0, 1, 64), indexing="ij")
    img = torch.stack([x, y, (x + y) / 2], -1)  # smooth: a lossy codec keeps it within a few levels
    path = write_image(tmp_path / f"a{suffix}", img, srgb=False, quality=95)
    back = read_image(path)
    assert back.shape == img.shape and (back - img).abs().mean() < 2 / 255 and (back - img).abs().max() < 12 / 255
    assert Image.open(path).format == ("WEBP" if suffix == ".webp" else "JPEG")
    small = write_image(tmp_path / f"b{suffix}", img, srgb=False, quality=20)
    assert small.stat().st_size < path.stat().st_size  # the quality is applied
    tagged = write_image(tmp_path / f"p{suffix}", img, srgb=False, icc=display_p3())
    assert Image.open(tagged).info.get("icc_profile") == display_p3() == read_icc(tagged)


def test_gray_and_out_of_range_values(tmp_path):
    img = torch.tensor([[-1.0, 0.5, 2.0]]).reshape(1, 3, 1)
    back = read_image(write_image(tmp_path / "g.png", img, srgb=False))
    assert back.shape == (1, 3, 3)  # gray repeated to RGB
    torch.testing.assert_close(back[0, :, 0], torch.tensor([0.0, 128 / 255, 1.0]))
    assert (back[..., 0] == back[..., 1]).all() and (back[..., 1] == back[..., 2]).all()
    assert to_uint8(np.zeros((2, 2, 3), np.float32)).dtype == torch.uint8


def test_write_and_read_errors(tmp_path):
    with pytest.raises(ShapeError, match="image"):
        write_image(tmp_path / "a.png", torch.zeros(4, 4, 2))
    with pytest.raises(InputError, match=r"\.png, \.jpg, \.jpeg, \.webp"):
        write_image(tmp_path / "a.bmp", torch.zeros(4, 4, 3))
    with pytest.raises(InputError, match="a.jpg: a JPEG has no alpha"):
        write_image(tmp_path / "a.jpg", torch.zeros(4, 4, 3), alpha=torch.ones(4, 4))
    with pytest.raises(InputError, match="quality"):
        write_image(tmp_path / "a.jpg", torch.zeros(4, 4, 3), quality=0)
    with pytest.raises(InputError, match="NaN"):
        write_image(tmp_path / "a.png", torch.full((4, 4, 3), float("nan")))
    with pytest.raises(InputError, match="does not exist"):
        write_image(tmp_path / "no" / "a.png", torch.zeros(4, 4, 3))
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(InputError, match="nothing.png"):
        read_image(tmp_path / "nothing.png")
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"\x89PNG but not really")
    with pytest.raises(InputError, match="bad.png"):
        read_image(bad)


def _jpeg(path, img, pix_fmt):
    """Write (H, W, 3) uint8 ``img`` as a JPEG with the chroma layout of ``pix_fmt`` (FFmpeg's mjpeg)."""
    from relightnet.io.image import _encode

    frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(img), format="rgb24").reformat(format=pix_fmt)
    path.write_bytes(_encode("mjpeg", frame))
    return path


def _gradient(h, w):
    yy, xx = np.mgrid[0:h, 0:w]
    return np.stack([xx * 200 // w + 20, yy * 200 // h + 30, 230 - xx * 150 // w], -1).astype(np.uint8)


@pytest.mark.parametrize("pix_fmt", ["yuvj444p", "yuvj422p", "yuvj420p"])
def test_jpeg_is_never_read_as_a_cut_out(tmp_path, pix_fmt):
    # Widths 17..49 cover every residue mod 16 (1..4 past a multiple of 16 broke FFmpeg's
    # YUV -> RGBA conversion: alpha-0 columns at the right edge, with wrong colours).
    for h in (16, 17):
        for w in range(17, 50):
            img = _gradient(h, w)
            path = _jpeg(tmp_path / f"p{w}x{h}.jpg", img, pix_fmt)
            rgb, alpha = read_image_alpha(path)
            assert alpha is None, (pix_fmt, w, h)
            assert read_alpha(path) is None
            assert rgb.shape == (h, w, 3)
            # JPEG's own loss is the same everywhere; the bug's columns were 6-47x worse than the rest.
            err = (rgb * 255 - torch.from_numpy(img).float()).abs()
            edge, rest = float(err[:, -4:].mean()), float(err[:, :-4].mean())
            assert err.max() < 40 and edge <= 2 * (rest + 1), (pix_fmt, w, h, edge, rest)


def test_rgba_and_gray_alpha_pngs_keep_their_alpha_exactly(tmp_path):
    from PIL import Image

    g = torch.Generator().manual_seed(1)
    rgb = torch.randint(0, 256, (16, 17, 3), generator=g, dtype=torch.uint8)
    a8 = torch.randint(0, 256, (16, 17), generator=g, dtype=torch.uint8)
    a8[0, 0] = 255
    path = write_image(tmp_path / "rgba.png", rgb, alpha=a8.float() / 255)
    back, alpha = read_image_alpha(path)
    torch.testing.assert_close((alpha * 255).round().to(torch.uint8), a8, rtol=0, atol=0)
    torch.testing.assert_close((back * 255).round().to(torch.uint8), rgb, rtol=0, atol=0)
    la = np.stack([np.full((16, 17), 90, np.uint8), a8.numpy()], -1)
    Image.fromarray(la, "LA").save(tmp_path / "la.png")
    back, alpha = read_image_alpha(tmp_path / "la.png")
    torch.testing.assert_close((alpha * 255).round().to(torch.uint8), a8, rtol=0, atol=0)
    assert ((back * 255).round() == 90).all()
    torch.testing.assert_close(read_mask(tmp_path / "la.png"), (a8.float() / 255 > 0.5).float())
    # A fully opaque RGBA file has no transparency to report; its mask is its gray level.
    opaque = write_image(tmp_path / "opaque.png", rgb, alpha=torch.ones(16, 17))
    assert read_alpha(opaque) is None
    assert read_mask(opaque).shape == (16, 17)


def test_rgb_jpeg_mask_reads_its_luminance(tmp_path):
    img = np.zeros((64, 97, 3), np.uint8)
    img[:, :18] = 255  # 18 of 97 columns white (18.6 %)
    for pix_fmt in ("yuvj444p", "yuvj422p", "yuvj420p"):
        mask = read_mask(_jpeg(tmp_path / f"m_{pix_fmt}.jpg", img, pix_fmt))
        assert mask.shape == (64, 97)
        assert abs(float(mask.mean()) - 18 / 97) < 0.01, pix_fmt
        assert mask[:, :16].all() and not mask[:, 20:].any()


def test_read_photo_of_a_phone_sized_jpeg_has_no_alpha(tmp_path):
    from relightnet._cli.inputs import read_photo

    path = _jpeg(tmp_path / "phone.jpg", _gradient(1000, 1203), "yuvj420p")
    img, mask, alpha = read_photo(str(path), None, mask_source="head")
    assert img.shape == (3, 1000, 1203)
    assert alpha is None and mask is None


@pytest.mark.parametrize("suffix", [".jpg", ".png", ".webp"])
def test_truncated_image_is_refused_in_one_line(tmp_path, suffix):
    from PIL import Image

    g = np.random.default_rng(3)
    img = g.integers(0, 256, (96, 131, 3), dtype=np.uint8)
    full = tmp_path / f"full{suffix}"
    Image.fromarray(img).save(full)
    data = full.read_bytes()
    cut = tmp_path / f"cut{suffix}"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match=r"cut\..*damaged or truncated") as e:
        read_image(cut)
    assert "\n" not in str(e.value)
    # Bytes after the end of the image (a phone's embedded video) are not damage.
    tail = tmp_path / f"tail{suffix}"
    tail.write_bytes(data + bytes(4096))
    assert read_image(tail).shape == (96, 131, 3)


def test_empty_text_and_looping_files_say_what_they_are(tmp_path):
    empty = tmp_path / "empty.png"
    empty.write_bytes(b"")
    text = tmp_path / "notes.jpg"
    text.write_text("not an image at all\n" * 20)
    (tmp_path / "a.png").symlink_to(tmp_path / "b.png")
    (tmp_path / "b.png").symlink_to(tmp_path / "a.png")
    for path, words in ((empty, r"is empty \(0 bytes\); expected an image"),
                        (text, r"cannot read an image: damaged, truncated or not an image \(expected one of .png"),
                        (tmp_path / "a.png", r"a symbolic link to nothing \(broken or looping\)")):
        with pytest.raises(InputError, match=rf"{path.name}: {words}") as e:
            read_image(path)
        assert "MP are refused" not in str(e.value) and "Errno" not in str(e.value)


def test_a_display_p3_photo_is_read_as_srgb_and_written_back_in_its_profile(tmp_path, caplog):
    """P3 codes → sRGB by the matrix maths (≤ 1 code: ½ for the output's rounding, the rest LittleCMS's
    16-bit tables); a written output is converted back into the profile and embeds its bytes."""
    from PIL import Image

    from relightnet.io.icc import photo_profile, read_icc

    from .icc_profiles import P3, SRGB, display_p3, rgb_to_xyz

    icc = display_p3()
    g = np.random.default_rng(5)
    codes = g.integers(0, 256, (24, 40, 3), dtype=np.uint8)
    codes[0, 0] = (255, 0, 0)  # the most saturated P3 red: outside sRGB, clipped to sRGB's red
    Image.fromarray(codes).save(tmp_path / "p3.png", icc_profile=icc)
    got = read_image(tmp_path / "p3.png").double().numpy() * 255
    lin = srgb_to_linear_np(codes / 255) @ np.linalg.solve(rgb_to_xyz(SRGB), rgb_to_xyz(P3)).T
    want = linear_to_srgb(torch.from_numpy(lin.clip(0, 1))).numpy() * 255
    assert np.abs(got - want).max() <= 1.0
    assert np.abs(got[0, 0] - (255, 0, 0)).max() <= 1.0
    assert photo_profile(tmp_path / "p3.png") == icc
    out = write_image(tmp_path / "out.png", torch.from_numpy(got / 255).float(), srgb=False, icc=icc)
    assert read_icc(out) == icc
    inside = ((lin >= 0) & (lin <= 1)).all(-1)  # colours sRGB holds come back to their P3 codes
    back = np.asarray(Image.open(out)).astype(int)
    assert np.abs(back - codes)[inside].max() <= 1
    # A damaged profile: a warning, sRGB assumed, no profile carried.
    Image.fromarray(codes).save(tmp_path / "bad.png", icc_profile=icc[:200])
    with caplog.at_level("WARNING"):
        assert (read_image(tmp_path / "bad.png") * 255).round().numpy().astype(np.uint8).tolist() == codes.tolist()
    assert "ICC profile is damaged" in caplog.text and photo_profile(tmp_path / "bad.png") is None
