import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.io import VideoWriter, read_video, video_info


def _frames(n, h=32, w=48):
    g = np.random.default_rng(0)
    return [g.integers(0, 256, (h, w, 3), dtype=np.uint8) for _ in range(n)]


def test_lossless_mkv_round_trip(tmp_path):
    frames = _frames(6)
    with VideoWriter(tmp_path / "a.mkv", fps=25) as w:
        for f in frames:
            w.write(f)
    back = list(read_video(tmp_path / "a.mkv"))
    assert len(back) == 6
    for a, b in zip(frames, back, strict=True):
        np.testing.assert_array_equal(a, b)
    assert video_info(tmp_path / "a.mkv").fps == pytest.approx(25)


def test_mp4_frame_count_size_and_float_frames(tmp_path):
    with VideoWriter(tmp_path / "a.mp4", fps=30) as w:
        for i in range(4):
            w.write(torch.full((32, 48, 3), i / 4.0))  # float linear -> sRGB 8-bit
    info = video_info(tmp_path / "a.mp4")
    assert info.n_frames == 4 and info.size == (32, 48)
    back = list(read_video(tmp_path / "a.mp4"))
    assert len(back) == 4 and back[0].shape == (32, 48, 3)
    assert back[3].mean() > back[1].mean() > back[0].mean()


def test_failure_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError), VideoWriter(tmp_path / "b.mp4") as w:
        w.write(_frames(1)[0])
        raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []


def test_odd_sizes_in_mp4_are_padded_to_yuv420p(tmp_path, caplog):
    import av

    g = np.random.default_rng(1)  # grey detail (full-resolution luma) and colour in blocks (4:2:0 chroma)
    frames = [np.repeat(g.integers(0, 255, (31, 47, 1), dtype=np.uint8), 3, axis=2) for _ in range(3)]
    for f in frames:
        f[:16, :24] = (200, 40, 40)
    with VideoWriter(tmp_path / "odd.mp4", fps=10) as w:
        for f in frames:
            w.write(f)
    assert "odd frame size 47x31 (width x height): padded to 48x32" in caplog.text
    with av.open(str(tmp_path / "odd.mp4")) as c:
        assert c.streams.video[0].codec_context.pix_fmt == "yuv420p"  # what every player decodes
    back = list(read_video(tmp_path / "odd.mp4"))
    assert len(back) == 3 and back[0].shape == (32, 48, 3)
    err = np.abs(back[1].astype(int) - frames[1].astype(int)[np.r_[:31, 30]][:, np.r_[:47, 46]])  # edges repeated
    assert max(err[:31, :47].mean(), err[31].mean(), err[:, 47].mean()) < 8  # lossy (~3.5); a wrong row: ~85


def test_bad_inputs(tmp_path):
    w = VideoWriter(tmp_path / "d.mkv")
    w.write(np.zeros((8, 8, 3), np.uint8))
    with pytest.raises(InputError, match="frame 1 is 9x8, expected 8x8"):
        w.write(np.zeros((9, 8, 3), np.uint8))
    w.abort()
    with pytest.raises(InputError, match="expected a video suffix"):
        VideoWriter(tmp_path / "e.avi")
    with pytest.raises(InputError, match="video file not found"):
        list(read_video(tmp_path / "missing.mp4"))
    (tmp_path / "junk.mp4").write_bytes(b"not a video")
    with pytest.raises(InputError, match="junk.mp4"):
        list(read_video(tmp_path / "junk.mp4"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["junk.mp4"]


def test_frames_with_masks_from_a_mask_video_and_its_checks(tmp_path):
    from relightnet.io.video_masks import frames_with_masks

    frames = _frames(3, 16, 16)
    masks = [np.zeros((16, 16, 3), np.uint8) for _ in range(3)]
    for m in masks:
        m[4:12, 4:12] = 255
    for name, items in (("v.mkv", frames), ("m.mkv", masks)):
        with VideoWriter(tmp_path / name, fps=5) as w:
            for f in items:
                w.write(f)
    info, n, pairs = frames_with_masks(tmp_path / "v.mkv", tmp_path / "m.mkv")
    got = list(pairs)
    assert len(got) == 3 and got[0][1].shape == (3, 16, 16) and got[0][2].sum() == 64
    masks[1][:] = 0
    with VideoWriter(tmp_path / "m0.mkv", fps=5) as w:
        for f in masks:
            w.write(f)
    with pytest.raises(InputError, match="mask of frame 1 .* is empty"):
        list(frames_with_masks(tmp_path / "v.mkv", tmp_path / "m0.mkv")[2])
    with VideoWriter(tmp_path / "m2.mkv", fps=5) as w:
        for f in (masks[0], masks[2]):
            w.write(f)
    with pytest.raises(InputError, match="m2.mkv: 2 masks for 3 video frames"):  # before any frame is decoded
        frames_with_masks(tmp_path / "v.mkv", tmp_path / "m2.mkv")


def _write_webm(path, frames, fps=5):
    """A VP8 webm (the container stores no frame count), written with PyAV directly."""
    import av

    with av.open(str(path), "w", format="webm") as c:
        s = c.add_stream("libvpx", rate=fps)
        s.width, s.height, s.pix_fmt = frames[0].shape[1], frames[0].shape[0], "yuv420p"
        s.options = {"crf": "4", "b:v": "1M"}
        for f in frames:
            for p in s.encode(av.VideoFrame.from_ndarray(f, format="rgb24")):
                c.mux(p)
        for p in s.encode():
            c.mux(p)


@pytest.mark.parametrize("video_ext, mask_ext", [(".mp4", ".mkv"), (".mkv", ".mp4"), (".mp4", ".webm"),
                                                 (".webm", ".mp4"), (".mkv", ".webm"), (".webm", ".mkv")])
def test_mask_videos_pair_across_containers(tmp_path, video_ext, mask_ext):
    """mkv and webm store no frame count: counted by decoding, so they pair with an mp4 both ways."""
    from relightnet.io import count_frames
    from relightnet.io.video_masks import frames_with_masks

    frames = [f.copy() for f in _frames(4, 32, 32)]
    masks = [np.zeros((32, 32, 3), np.uint8) for _ in range(4)]
    for m in masks:
        m[8:24, 8:24] = 255
    for name, items in ((f"v{video_ext}", frames), (f"m{mask_ext}", masks)):
        if name.endswith(".webm"):
            _write_webm(tmp_path / name, items)
        else:
            with VideoWriter(tmp_path / name, fps=5) as w:
                for f in items:
                    w.write(f)
    assert count_frames(tmp_path / f"m{mask_ext}") == 4
    info, n, pairs = frames_with_masks(tmp_path / f"v{video_ext}", tmp_path / f"m{mask_ext}")
    got = list(pairs)
    assert n == 4 and len(got) == 4 and all(abs(int(m.sum()) - 256) <= 16 for _, _, m in got)
    if mask_ext != ".mp4":  # one mask short: refused, naming the counts
        short = tmp_path / f"short{mask_ext}"
        if mask_ext == ".webm":
            _write_webm(short, masks[:3])
        else:
            with VideoWriter(short, fps=5) as w:
                for f in masks[:3]:
                    w.write(f)
        with pytest.raises(InputError, match="3 masks"):
            list(frames_with_masks(tmp_path / f"v{video_ext}", short)[2])


def test_count_frames_trusts_no_container_claim(tmp_path):
    """An mp4 whose stts says 20 M frames holds 5: count_frames counts the packets really there."""
    import struct

    from relightnet.io import VideoWriter, count_frames, video_info

    with VideoWriter(tmp_path / "v.mp4", fps=10) as w:
        for i in range(5):
            w.write(np.full((32, 32, 3), 40 * i, np.uint8))
    data = bytearray((tmp_path / "v.mp4").read_bytes())
    at = data.find(b"stts")
    data[at + 12:at + 16] = struct.pack(">I", 20_000_000)
    (tmp_path / "lie.mp4").write_bytes(bytes(data))
    assert video_info(tmp_path / "lie.mp4").n_frames == 20_000_000  # the claim, for progress bars only
    assert count_frames(tmp_path / "lie.mp4") == count_frames(tmp_path / "v.mp4") == 5


def test_frames_above_1080p_are_encoded_without_b_frames(tmp_path):
    """Above 1080p libx264 holds few frames (short lookahead, no B-frames): its memory stays bounded."""
    import av

    from relightnet.io.video import X264_LARGE_PIXELS

    rng = np.random.default_rng(0)
    for (h, w), big in (((1090, 2000), True), ((120, 160), False)):
        assert (h * w > X264_LARGE_PIXELS) == big
        base = rng.integers(0, 255, (h // 8, w // 8, 3), np.uint8).repeat(8, 0).repeat(8, 1)
        with VideoWriter(tmp_path / f"v{w}.mp4", fps=30) as wr:
            for i in range(8):
                wr.write(np.roll(base, 3 * i, 1))
        with av.open(str(tmp_path / f"v{w}.mp4")) as c:
            kinds = {int(f.pict_type) for f in c.decode(video=0)}  # FFmpeg's AVPictureType: 3 is B
        assert (3 in kinds) != big, kinds


def test_a_large_lossless_mkv_is_warned_about(tmp_path, monkeypatch, caplog):
    """ffv1's memory for one frame grows with its pixels (~70 bytes each): frames above FFV1_LARGE_PIXELS
    into an .mkv are written with a warning that says so; an .mp4 or a smaller frame gets none."""
    import logging

    from relightnet.io import video

    monkeypatch.setattr(video, "FFV1_LARGE_PIXELS", 200)
    with caplog.at_level(logging.WARNING, logger="relightnet.io.video"):
        for name, side in (("big.mkv", 16), ("small.mkv", 12), ("big.mp4", 16)):
            with VideoWriter(tmp_path / name, fps=5) as w:
                w.write(np.zeros((side, side, 3), np.uint8))
    warned = [r.getMessage() for r in caplog.records if "ffv1" in r.getMessage()]
    assert len(warned) == 1 and "big.mkv" in warned[0] and "16x16" in warned[0], warned


def test_gray_mkv_keeps_every_grey_level_in_one_plane(tmp_path):
    """Masks written with ``gray=True``: one 8-bit plane in the .mkv (ffv1 ``gray``), read back as (H, W, 3)
    frames equal to what was written, every level 0-255; an .mp4 is written as usual."""
    import av

    g = np.repeat(np.arange(256, dtype=np.uint8)[None, :, None], 3, -1).repeat(4, 0)  # (4, 256, 3)
    with VideoWriter(tmp_path / "m.mkv", fps=5, gray=True) as w:
        w.write(g)
        w.write(255 - g)
    with av.open(str(tmp_path / "m.mkv")) as c:
        assert c.streams.video[0].codec_context.pix_fmt == "gray"
    frames = list(read_video(tmp_path / "m.mkv"))
    assert len(frames) == 2 and np.array_equal(frames[0], g) and np.array_equal(frames[1], 255 - g)
    with VideoWriter(tmp_path / "m.mp4", fps=5, gray=True) as w:
        w.write(g)
    with av.open(str(tmp_path / "m.mp4")) as c:
        assert c.streams.video[0].codec_context.pix_fmt == "yuv420p"


def _packet_pts(path) -> tuple[object, list[int]]:
    """The video stream's time base and its packets' pts in display order."""
    import av

    with av.open(str(path)) as c:
        s = c.streams.video[0]
        return s.time_base, sorted(p.pts for p in c.demux(s) if p.size)


@pytest.mark.parametrize(("suffix", "tick"), [(".mp4", 1 / 90000), (".mkv", 1 / 1000)])
def test_frames_with_times_keep_them_on_the_writers_clock(tmp_path, caplog, suffix, tick):
    from fractions import Fraction

    from relightnet.io.video import frame_times
    from tests.io.timed_media import VFR_TIMES

    times = [*VFR_TIMES[:31], VFR_TIMES[30], *VFR_TIMES[31:]]  # frame 31 repeats frame 30's time
    out = tmp_path / f"vfr{suffix}"
    with VideoWriter(out, fps=25) as w:
        for f, t in zip(_frames(len(times), 16, 16), times, strict=True):
            w.write(f, time=t)
    tb, pts = _packet_pts(out)
    assert tb == Fraction(tick).limit_denominator(90000)
    assert all(b > a for a, b in zip(pts, pts[1:], strict=False))  # strictly increasing
    want = np.round(np.array(times) / tick)
    want[31] = want[30] + 1  # the repeated time: one tick later
    assert np.abs(np.array(pts) - want).max() <= 1  # exact on the clock, within a tick
    assert "is not after the previous frame's" in caplog.text
    np.testing.assert_allclose(frame_times(out), want * tick, rtol=0, atol=tick)
    assert len(list(read_video(out))) == len(times)


@pytest.mark.parametrize("clip", ["vfr", "late", "both-late"])
@pytest.mark.parametrize(("src_name", "acodec", "fmt"), [("in.mp4", "aac", "mp4"),
                                                         ("in.mkv", "pcm_s16le", "matroska")])
@pytest.mark.parametrize("out_name", ["out.mp4", "out.mkv"])
def test_writer_keeps_vfr_and_a_late_start_in_sync_with_the_sound(tmp_path, clip, src_name, acodec, fmt, out_name):
    from relightnet.io.video import frame_times
    from tests.io import timed_media as media

    late = media.LATE_TIMES
    times, clicks, start = {"vfr": (media.VFR_TIMES, [0.5, 1.0, 1.5], 0.0), "late": (late, [0.5, 1.0], 0.0),
                            "both-late": ([t + 0.2 for t in late], [0.7, 1.2], 0.2)}[clip]  # sound from 0.2 s
    src = media.write_timed_clip(tmp_path / src_name, times, clicks, audio_start=start, acodec=acodec, fmt=fmt)
    out = tmp_path / out_name
    with VideoWriter(out, fps=video_info(src).fps, audio_from=src) as w:
        for f, t in zip(read_video(src), frame_times(src), strict=True):
            w.write(f, time=t)
    # Every frame against the sound as in the source, within the ms clocks of mkv and of mp4's edit
    # lists (under 1 ms per stream; half a frame would be 17 ms).
    assert np.abs(media.av_offsets(src, out)).max() <= 2e-3
    shown, heard = media.decoded_frame_times(out), media.click_times(out)
    np.testing.assert_allclose(np.diff(shown), np.diff(times), rtol=0, atol=1e-3)  # VFR stays VFR
    # The late video still starts as the first click (0.5 s into the sound) sounds; the clicks keep their spacing.
    assert shown[0] - heard[0] == pytest.approx(times[0] - clicks[0], abs=2e-3)
    np.testing.assert_allclose(np.diff(heard), np.diff(clicks), rtol=0, atol=1e-3)
