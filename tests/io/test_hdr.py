"""HDR video read as SDR: the BT.2100 transfer functions against published values, the tone mapping,
HLG and PQ clips made with PyAV (10-bit HEVC, lossless) decoded through the reader against an
independent float64 computation, SDR clips decoded as before and written files tagged BT.709."""

import av
import numpy as np
import pytest
import torch

from relightnet.io import VideoWriter, hdr, read_video
from tests.io.hdr_media import write_hevc10
from tests.io.timed_media import write_timed_clip

#: BT.2020 → BT.709 linear RGB as published (ITU-R BT.2087, four decimals).
BT2087 = np.array([[1.6605, -0.5876, -0.0728], [-0.1246, 1.1329, -0.0083], [-0.0182, -0.1006, 1.1187]])
H, W, BLOCK = 32, 64, 16  # 2 x 4 flat patches of 16 x 16 (8 x 8 chroma samples each)


def test_hlg_reference_points_and_round_trip():
    t = torch.tensor([0.0, 1 / 12, 1.0], dtype=torch.float64)
    np.testing.assert_allclose(hdr.hlg_oetf(t), [0.0, 0.5, 1.0], atol=1e-6)  # BT.2100 table 5
    e = torch.linspace(0, 1, 1001, dtype=torch.float64)
    np.testing.assert_allclose(hdr.hlg_inverse_oetf(hdr.hlg_oetf(e)), e, atol=1e-12)
    # BT.2408: reference white is HLG 75% on a 1000 cd/m² display, 203 cd/m²
    grey = hdr.hlg_inverse_oetf(torch.full((3,), 0.75, dtype=torch.float64))
    np.testing.assert_allclose(hdr.hlg_ootf(grey), [203.0] * 3, atol=0.5)
    np.testing.assert_allclose(hdr.hlg_ootf(torch.ones(3, dtype=torch.float64)), [1000.0] * 3)


def test_pq_reference_points_and_round_trip():
    nits = torch.tensor([0.0, 100.0, 203.0, 1000.0, 10000.0], dtype=torch.float64)
    # BT.2100 / BT.2408: 100 cd/m² at 50.8%, reference white 203 cd/m² at 58.1%, 1000 cd/m² at 75.2%
    np.testing.assert_allclose(hdr.pq_inverse_eotf(nits), [0.0, 0.5081, 0.5807, 0.7518, 1.0], atol=1e-4)
    np.testing.assert_allclose(hdr.pq_eotf(hdr.pq_inverse_eotf(nits)), nits, rtol=1e-9, atol=1e-6)
    v = torch.linspace(0, 1, 1001, dtype=torch.float64)
    np.testing.assert_allclose(hdr.pq_inverse_eotf(hdr.pq_eotf(v))[1:], v[1:], atol=1e-9)


def test_bt2020_to_bt709_matrix_is_the_published_one():
    np.testing.assert_allclose(hdr.BT2020_TO_BT709, BT2087, atol=6e-5)
    np.testing.assert_allclose(hdr.BT2020_TO_BT709.sum(1), 1.0, atol=1e-12)  # white stays white


def test_tone_map_keeps_the_shadows_and_brings_the_peak_to_white():
    peak = hdr.HLG_PEAK / hdr.REFERENCE_WHITE
    m = torch.linspace(0, peak * 1.2, 2001, dtype=torch.float64)
    out = hdr.tone_map(m.repeat(3, 1), peak)[0]
    below = m <= hdr.KNEE
    np.testing.assert_allclose(out[below], m[below], atol=1e-12)
    assert (out.diff() >= 0).all() and out.max() == 1.0
    assert hdr.tone_map(torch.full((3,), peak, dtype=torch.float64), peak)[0] == pytest.approx(1.0)
    eps = 1e-6
    above = hdr.tone_map(torch.full((3, 1), hdr.KNEE + eps, dtype=torch.float64), peak)[0, 0].item()
    assert (above - hdr.KNEE) / eps == pytest.approx(1.0, abs=1e-4)  # slope 1 at the knee
    colour = hdr.tone_map(torch.tensor([3.0, 1.5, 0.3], dtype=torch.float64), peak)
    np.testing.assert_allclose(colour / colour[0], [1.0, 0.5, 0.1])  # hue and ratios kept


def test_ycbcr_to_rgb_ranges_matrices_and_widened_codes():
    bt709, bt2020 = (0.2126, 0.0722), (0.2627, 0.0593)
    codes = torch.tensor([[64.0, 940.0, 0.0], [512.0, 512.0, 512.0], [512.0, 512.0, 512.0]])  # (3, 3): 3 pixels
    np.testing.assert_allclose(hdr.ycbcr_to_rgb(codes, 10, bt2020, False)[:, :2].T, [[0.0] * 3, [1.0] * 3], atol=1e-6)
    full = hdr.ycbcr_to_rgb(torch.tensor([[0.0, 1023.0], [512.0, 512.0], [512.0, 512.0]]), 10, bt2020, True)
    np.testing.assert_allclose(full[0], [0.0, 1.0], atol=1e-6)
    # 8-bit BT.709 red (unrounded codes), and the same codes widened to 16 bits by a shift of 8
    red = torch.tensor([[16 + 219 * 0.2126], [128 - 112 * 0.2126 / 0.9278], [240.0]])
    np.testing.assert_allclose(hdr.ycbcr_to_rgb(red, 8, bt709, False)[:, 0], [1, 0, 0], atol=1e-5)
    np.testing.assert_allclose(hdr.ycbcr_to_rgb(red * 256, 8, bt709, False, shift=8)[:, 0], [1, 0, 0], atol=1e-5)
    rgb = torch.rand(3, 50, dtype=torch.float64)  # BT.2020 ncl: the test's own encoding inverted
    back = hdr.ycbcr_to_rgb(torch.from_numpy(_codes(rgb.T.numpy()).T.astype(np.float32)), 10, bt2020, False)
    np.testing.assert_allclose(back, rgb, atol=2e-3)  # 10-bit rounding of Y'CbCr


def _patches(transfer: str) -> np.ndarray:
    """(8, 3) BT.2020 R'G'B' signals: black, greys, reference white, peak, saturated and skin colours."""
    if transfer == "hlg":  # scene light in [0, 1]
        scene = [[0, 0, 0], [0.02, 0.02, 0.02], [0.265, 0.265, 0.265], [1, 1, 1],
                 [0.05, 0.6, 0.05], [0.6, 0.1, 0.05], [0.3, 0.18, 0.12], [0.1, 0.15, 0.4]]
        return hdr.hlg_oetf(torch.tensor(scene, dtype=torch.float64)).numpy()
    nits = [[0, 0, 0], [10, 10, 10], [203, 203, 203], [1000, 1000, 1000],
            [20, 400, 20], [500, 60, 30], [150, 90, 60], [40, 60, 300]]
    return hdr.pq_inverse_eotf(torch.tensor(nits, dtype=torch.float64)).numpy()


def _codes(rgb: np.ndarray) -> np.ndarray:
    """(..., 3) BT.2020 R'G'B' → 10-bit limited-range Y'CbCr codes (BT.2020 ncl), rounded."""
    y = rgb @ np.array([0.2627, 0.6780, 0.0593])
    cb, cr = (rgb[..., 2] - y) / 1.8814, (rgb[..., 0] - y) / 1.4746
    return np.round(np.stack([64 + 876 * y, 512 + 896 * cb, 512 + 896 * cr], -1)).astype(np.uint16)


def _expected_srgb(codes: np.ndarray, transfer: str) -> np.ndarray:
    """The reader's result computed independently in float64: (..., 3) codes → (..., 3) uint8 sRGB."""
    codes = codes.astype(np.float64)
    y, cb, cr = (codes[..., 0] - 64) / 876, (codes[..., 1] - 512) / 896, (codes[..., 2] - 512) / 896
    r, b = y + 1.4746 * cr, y + 1.8814 * cb
    rgb = np.clip(np.stack([r, (y - 0.2627 * r - 0.0593 * b) / 0.6780, b], -1), 0, 1)
    if transfer == "pq":
        p = rgb ** (32 / 2523)
        light = 10000 * (np.maximum(p - 0.8359375, 0) / (18.8515625 - 18.6875 * p)) ** (16384 / 2610)
    else:
        a, bb = 0.17883277, 1 - 4 * 0.17883277
        c = 0.5 - a * np.log(4 * a)
        e = np.where(rgb <= 0.5, rgb**2 / 3, (np.exp((rgb - c) / a) + bb) / 12)
        light = 1000 * (e @ np.array([0.2627, 0.6780, 0.0593]))[..., None] ** 0.2 * e
    x = np.maximum(light / 203 @ BT2087.T, 0)
    peak, knee = 1000 / 203, 0.75
    m = x.max(-1, keepdims=True)
    d = np.maximum(m - knee, 0)
    shoulder = knee + d * (1 + d * (1 - knee) / (peak - knee) ** 2) / (1 + d / (1 - knee))
    sdr = np.clip(np.where(m > knee, x * shoulder / np.maximum(m, 1e-12), x), 0, 1)
    srgb = np.where(sdr <= 0.0031308, 12.92 * sdr, 1.055 * sdr ** (1 / 2.4) - 0.055)
    return np.round(srgb * 255).astype(np.uint8)


def _write_hevc(path, codes: np.ndarray, trc: int, n: int = 2) -> None:
    """``n`` frames of (8, 3) patch codes as 10-bit 4:2:0 HEVC (lossless), tagged BT.2020 + ``trc``."""
    img = codes.reshape(2, 4, 3).repeat(BLOCK, 0).repeat(BLOCK, 1)  # (H, W, 3)
    planes = (img[..., 0], img[::2, ::2, 1], img[::2, ::2, 2])  # flat patches: 4:2:0 exactly
    write_hevc10(path, [planes] * n, (W, H), trc, lossless=True)


@pytest.mark.parametrize("transfer, trc", [("hlg", 18), ("pq", 16)])
def test_hdr_clips_are_read_tone_mapped_to_srgb(tmp_path, caplog, transfer, trc):
    codes = _codes(_patches(transfer))
    path = tmp_path / f"{transfer}.mp4"
    _write_hevc(path, codes, trc)
    with av.open(str(path)) as c:  # the codec is lossless: the reader gets exactly these codes
        f = next(c.decode(video=0))
        assert (f.color_trc, f.color_primaries, f.colorspace) == (trc, 9, 9)
        np.testing.assert_array_equal(f.to_ndarray()[:H:BLOCK, ::BLOCK], codes.reshape(2, 4, 3)[..., 0])
    with caplog.at_level("WARNING"):
        frames = list(read_video(path))
    assert caplog.text.count("an HDR video") == 1 and "tone-mapped to SDR" in caplog.text
    assert len(frames) == 2 and frames[0].shape == (H, W, 3) and frames[0].dtype == np.uint8
    got = frames[1].reshape(2, BLOCK, 4, BLOCK, 3)[:, 4:12, :, 4:12]  # patch interiors (chroma upsampling)
    expected = _expected_srgb(codes, transfer).reshape(2, 1, 4, 1, 3)
    # float32 against float64 arithmetic: at most one 8-bit code where a value falls near a rounding edge
    assert np.abs(got.astype(int) - expected).max() <= 1
    # reference white: 0.875 linear (KNEE and its shoulder), sRGB 240.4, give or take its 10-bit codes; the peak: white
    assert np.abs(got[0, 0, 2, 0].astype(int) - 240).max() <= 1 and (got[0, :, 3] == 255).all()


def test_sdr_clips_decode_as_ffmpeg_converts_them(tmp_path):
    g = np.random.default_rng(0)
    for name, fmt, tags in (("tagged.mp4", "yuv420p", (1, 1, 1, 1)), ("ten.mp4", "yuv420p10le", (9, 14, 9, 1)),
                            ("untagged.mp4", "yuv420p", None)):
        with av.open(str(tmp_path / name), "w") as c:
            s = c.add_stream("libx264", rate=10)
            s.width, s.height, s.pix_fmt = W, H, fmt
            if tags:
                cc = s.codec_context
                cc.color_primaries, cc.color_trc, cc.colorspace, cc.color_range = tags
            for i in range(2):
                f = av.VideoFrame.from_ndarray(g.integers(0, 256, (H, W, 3), dtype=np.uint8), format="rgb24")
                f.pts = i
                for p in s.encode(f):
                    c.mux(p)
            for p in s.encode():
                c.mux(p)
        with av.open(str(tmp_path / name)) as c:
            before = [f.to_ndarray(format="rgb24") for f in c.decode(video=0)]
        for a, b in zip(before, read_video(tmp_path / name), strict=True):
            np.testing.assert_array_equal(a, b)


def test_written_videos_are_tagged_sdr_and_keep_their_colours(tmp_path):
    frame = np.zeros((H, W, 3), np.uint8)
    frame[:, :32] = (230, 20, 20)  # saturated: a BT.601 / BT.709 matrix mismatch moves it by ~20 codes
    frame[:, 32:] = (30, 180, 90)
    write_timed_clip(tmp_path / "sound.mp4", [i / 30 for i in range(3)], [0.05])
    for name, tags, sound in (("a.mp4", (1, 1, 1, 1), None), ("a.mkv", (1, 13, 0, 2), None),
                              ("b.mp4", (1, 1, 1, 1), tmp_path / "sound.mp4")):  # the tags kept when muxed
        with VideoWriter(tmp_path / name, fps=10, audio_from=sound) as w:
            w.write(frame)
        with av.open(str(tmp_path / name)) as c:
            assert len(c.streams.audio) == (sound is not None)
            cc = c.streams.video[0].codec_context
            assert (cc.color_primaries, cc.color_trc, cc.colorspace, cc.color_range) == tags
        back = next(read_video(tmp_path / name)).astype(int)
        assert np.abs(back[4:-4, 4:28] - frame[4:-4, 4:28]).max() <= 2
        assert np.abs(back[4:-4, 36:-4] - frame[4:-4, 36:-4]).max() <= 2
