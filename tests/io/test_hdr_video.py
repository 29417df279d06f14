"""HDR kept HDR: linear frames read and written as 10-bit HLG/PQ, tags and metadata carried over."""

import av
import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.io import VideoWriter, read_video
from relightnet.io.hdr import HLG_PEAK, PQ_PEAK, content_peak, sdr_from_linear
from relightnet.io.hdr_video import (
    HDR_GAIN_MAX,
    HdrClip,
    HdrFormat,
    HdrVideoWriter,
    hdr_behind,
    hdr_format,
    hdr_from_sdr,
    linear_to_signal,
    read_linear_video,
    ycbcr_codes,
)


def _light(h=32, w=48, seed=0):
    """(3, h, w) linear light up to 4x reference white: smooth ramps plus noise, inside BT.709's gamut."""
    g = torch.Generator().manual_seed(seed)
    y, x = torch.meshgrid(torch.linspace(0, 1, h), torch.linspace(0, 1, w), indexing="ij")
    ramps = torch.stack([x * 4, y * 2, (x + y) / 2])
    return ramps + 0.02 + 0.1 * torch.rand(3, h, w, generator=g)


def _codes(light, transfer):
    return ycbcr_codes(linear_to_signal(light, transfer))


@pytest.mark.parametrize("transfer", ["hlg", "pq"])
def test_lossless_4_4_4_round_trip_keeps_the_codes(tmp_path, transfer):
    # ffv1 stores the 10-bit codes exactly: what is read back re-encodes to the same codes within the
    # rounding of one step (the decoder's 65537-step curve tables move a signal by 1/150 step).
    light = _light()
    path = tmp_path / "hdr.mkv"
    with HdrVideoWriter(path, HdrFormat(transfer), fps=10) as w:
        w.write(light)
        w.write(light.permute(1, 2, 0))  # (H, W, 3) is taken too
    frames = list(read_linear_video(path))
    assert len(frames) == 2 and frames[0].shape == (3, 32, 48)
    for back in frames:
        assert (_codes(back, transfer) - _codes(light, transfer)).abs().max() <= 1
    assert hdr_format(path) == HdrFormat(transfer)
    with av.open(str(path)) as c:
        cc = c.streams.video[0].codec_context
        assert (cc.name, cc.pix_fmt, cc.color_primaries, cc.colorspace) == ("ffv1", "yuv444p10le", 9, 9)
        assert cc.color_trc == {"hlg": 18, "pq": 16}[transfer]


def test_linear_to_signal_inverts_the_reader_at_reference_points():
    # PQ: reference white (203 cd/m²) is signal 0.58 (BT.2408); HLG: it is 0.75 on a 1000 cd/m² display.
    white = torch.ones(3, 1)
    assert linear_to_signal(white, "pq")[:, 0] == pytest.approx([0.5807] * 3, abs=2e-4)
    assert linear_to_signal(white, "hlg")[:, 0] == pytest.approx([0.7500] * 3, abs=3e-3)
    assert linear_to_signal(torch.zeros(3, 1), "pq").abs().max() < 1e-6
    # out of BT.2020's gamut or negative: clipped to its black, never NaN
    assert torch.isfinite(linear_to_signal(torch.tensor([[-1.0], [2.0], [0.0]]), "hlg")).all()


def test_hevc_output_is_tagged_and_keeps_the_pq_metadata(tmp_path):
    fmt = HdrFormat("pq", max_cll=1600, max_fall=400, mastering_peak=4000.0)
    light = _light(64, 96)
    path = tmp_path / "hdr.mp4"
    with HdrVideoWriter(path, fmt, fps=10) as w:
        for _ in range(3):
            w.write(light)
    assert hdr_format(path) == fmt
    with av.open(str(path)) as c:
        s = c.streams.video[0]
        cc = s.codec_context
        assert (cc.name, cc.pix_fmt, s.codec_tag) == ("hevc", "yuv420p10le", "hvc1")
        assert (cc.color_primaries, cc.color_trc, cc.colorspace) == (9, 16, 9)
        first = next(c.decode(video=0))
        assert content_peak(first) == 1600.0  # MaxCLL before the mastering display's peak
    back = next(read_linear_video(path))
    lum = torch.tensor([0.2126, 0.7152, 0.0722]) @ light.reshape(3, -1)
    lum_back = torch.tensor([0.2126, 0.7152, 0.0722]) @ back.reshape(3, -1)
    # lossy HEVC, 4:2:0: the luminance within a few per cent (a 10-bit PQ step is ~1% here)
    assert ((lum_back - lum).abs() / lum).median() < 0.02


def test_content_peak_of_hlg_and_of_pq_without_metadata(tmp_path):
    for transfer, want in (("hlg", HLG_PEAK), ("pq", PQ_PEAK)):
        path = tmp_path / f"{transfer}.mkv"
        with HdrVideoWriter(path, HdrFormat(transfer), fps=10) as w:
            w.write(_light())
        with av.open(str(path)) as c:
            assert content_peak(next(c.decode(video=0))) == want


def test_the_sdr_reading_follows_the_pq_clips_own_peak(tmp_path):
    # A PQ clip is tone-mapped to its own MaxCLL: the reader's frame is the linear frame tone-mapped to that peak.
    light = _light(64, 96) * 5  # up to 20x reference white, 4000 cd/m²
    path = tmp_path / "pq4000.mp4"
    with HdrVideoWriter(path, HdrFormat("pq", max_cll=4000, max_fall=100), fps=10) as w:
        w.write(light)
    sdr = torch.from_numpy(next(read_video(path))).permute(2, 0, 1)
    back = next(read_linear_video(path))
    assert torch.equal(sdr, sdr_from_linear(back.clone(), 4000.0))
    assert not torch.equal(sdr, sdr_from_linear(back.clone(), PQ_PEAK))


def test_hdr_from_sdr_keeps_untouched_pixels_and_scales_relit_ones():
    hdr = _light() * 1.5
    sdr = torch.rand(3, 32, 48, generator=torch.Generator().manual_seed(1)) * 0.3 + 0.3  # sRGB, x2 stays below 1
    out = hdr_from_sdr(sdr, sdr, hdr)
    torch.testing.assert_close(out, hdr, rtol=0, atol=1e-6)
    # twice the light in linear: the HDR pixel doubles too, but for eps / (linear SDR + eps) <= 1.4% here
    from relightnet.color import linear_to_srgb, srgb_to_linear

    doubled = linear_to_srgb(srgb_to_linear(sdr) * 2)
    torch.testing.assert_close(hdr_from_sdr(doubled, sdr, hdr), 2 * hdr, rtol=0.015, atol=1e-5)
    # uint8 frames as the video job hands them over; a black SDR pixel's gain stays bounded
    u8 = (sdr * 255).round().to(torch.uint8)
    assert hdr_from_sdr(u8, u8, hdr).sub(hdr).abs().max() < 1e-5
    black = torch.zeros_like(sdr)
    black[:, 0, 0] = 1.0
    out = hdr_from_sdr(black, torch.zeros_like(sdr), hdr)
    assert float(out[:, 0, 0].max()) <= 1.0 + hdr[:, 0, 0].max() * HDR_GAIN_MAX
    with pytest.raises(ValueError, match="edited frame"):
        hdr_from_sdr(sdr[:, :5], sdr, hdr)


def test_hdr_behind_keeps_the_frame_where_nothing_is_drawn():
    from relightnet.color import srgb_to_linear

    hdr = _light() * 1.5
    sdr = (torch.rand(3, 32, 48, generator=torch.Generator().manual_seed(2)) * 255).round().to(torch.uint8)
    drawn = torch.zeros(32, 48, dtype=torch.bool)
    drawn[8:20, 10:30] = True
    composite = sdr.clone()
    composite[:, drawn] = 7  # an avatar, dark: a gain to the bright frame behind it would bring its highlights
    out = hdr_behind(composite, sdr, hdr, drawn)
    torch.testing.assert_close(out[:, ~drawn], hdr[:, ~drawn], rtol=0, atol=1e-6)
    torch.testing.assert_close(out[:, drawn], srgb_to_linear(torch.full((3, int(drawn.sum())), 7 / 255)))
    half = hdr_behind(composite, sdr, hdr, drawn.float() * 0.5)  # a partly drawn pixel keeps half the HDR part
    torch.testing.assert_close(half, (out + hdr_behind(composite, sdr, hdr, drawn.float() * 0)) / 2)
    with pytest.raises(ValueError, match="drawn"):
        hdr_behind(composite, sdr, hdr, drawn[:5])


def test_an_sdr_clip_is_refused_before_any_frame(tmp_path):
    path = tmp_path / "sdr.mkv"
    with VideoWriter(path, fps=10) as w:
        w.write(np.full((16, 16, 3), 100, np.uint8))
    assert hdr_format(path) is None
    with pytest.raises(InputError, match="not an HDR video"):
        HdrClip(path)
    with pytest.raises(InputError, match="not HDR"):
        next(read_linear_video(path))
    with pytest.raises(ValueError, match="transfer"):
        HdrFormat("srgb")


def test_non_finite_frames_are_refused_and_leave_no_file(tmp_path):
    path = tmp_path / "bad.mkv"
    light = _light()
    light[0, 0, 0] = float("nan")
    with pytest.raises(InputError, match="non-finite"), HdrVideoWriter(path, HdrFormat("hlg")) as w:
        w.write(light)
    assert not path.exists() and not list(tmp_path.iterdir())


def test_conversions_in_row_bands_are_the_whole_frames(tmp_path, monkeypatch):
    """The readers, the writer and the carry convert a frame band by band (hdr.BAND_ROWS rows, bounding
    their temporaries): each pixel on its own, so bands of 4 rows give what one band of the frame gives
    (to float32 rounding: a 3 x 3 matrix product may sum in another order for another band's width, which
    can move a rounded 8- or 10-bit code by one)."""
    from relightnet.io import hdr

    light, got = _light(h=37), {}
    sdr = (torch.rand(3, 37, 48, generator=torch.Generator().manual_seed(3)) * 255).round().to(torch.uint8)
    drawn = torch.rand(37, 48, generator=torch.Generator().manual_seed(4)) > 0.5
    for rows in (4, 10**6):
        monkeypatch.setattr(hdr, "BAND_ROWS", rows)
        path = tmp_path / f"b{rows}.mkv"
        with HdrVideoWriter(path, HdrFormat("pq"), fps=10) as w:
            w.write(light)
            w.write(light.permute(1, 2, 0) * 0.5)
        got[rows] = (list(read_linear_video(path)), list(read_video(path)), hdr_from_sdr(sdr, sdr, light),
                     hdr_behind(sdr.flip(1), sdr, light, drawn))
    small, whole = got[4], got[10**6]
    for a, b in zip(small[0], whole[0], strict=True):
        torch.testing.assert_close(a, b, rtol=1e-6, atol=1e-7)
    for a, b in zip(small[1], whole[1], strict=True):
        assert np.abs(a.astype(int) - b).max() <= 1
    torch.testing.assert_close(small[2], whole[2], rtol=1e-6, atol=1e-7)  # vector or scalar pow: one ulp
    torch.testing.assert_close(small[3], whole[3], rtol=1e-6, atol=1e-7)
    with av.open(str(tmp_path / "b4.mkv")) as a, av.open(str(tmp_path / f"b{10**6}.mkv")) as b:
        for fa, fb in zip(a.decode(video=0), b.decode(video=0), strict=True):  # the same 10-bit codes, to one
            for pa, pb in zip(fa.planes, fb.planes, strict=True):
                assert np.abs(np.frombuffer(pa, np.uint16).astype(int) - np.frombuffer(pb, np.uint16)).max() <= 1
