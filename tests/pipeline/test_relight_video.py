import numpy as np
import pytest

from relightnet.cli import main
from relightnet.io import read_video, video_info
from relightnet.pipeline import VideoLightSettings

pytestmark = pytest.mark.slow  # video jobs through the CLI (segmentation, CNN per frame, encoding)


def test_relight_video_streams_all_frames(tmp_path, masked_clip):
    video, masks = masked_clip(tmp_path)
    out = tmp_path / "relit.mkv"
    assert main(["-q", "relight-video", str(video), "--masks", str(masks), "--light", "sunset", "--turntable", "90",
                 "--out", str(out)]) == 0
    frames = list(read_video(out))
    assert len(frames) == 3 and frames[0].shape == (64, 48, 3)
    src = list(read_video(video))
    # The background (outside the masks) is unchanged (lossless mkv).
    np.testing.assert_array_equal(frames[0][:, :10], src[0][:, :10])
    assert video_info(out).fps == 12


def test_relight_video_bad_inputs_leave_nothing(tmp_path, capsys, masked_clip):
    video, masks = masked_clip(tmp_path)
    (masks / "002.png").unlink()
    out = tmp_path / "r.mp4"
    assert main(["relight-video", str(video), "--masks", str(masks), "--light", "studio", "--out", str(out)]) == 1
    assert "2 masks" in capsys.readouterr().err and not out.exists()
    assert main(["relight-video", str(tmp_path / "nope.mp4"), "--masks", str(masks), "--light", "studio",
                 "--out", str(out)]) == 1
    assert "not found" in capsys.readouterr().err


def test_relight_video_keeps_the_sound(tmp_path, masked_clip, clip_with_sound):
    import av

    from relightnet.io.audio import add_audio

    video, masks = masked_clip(tmp_path)
    tone = clip_with_sound(tmp_path / "tone.mp4")
    with_sound = add_audio(video, tone, tmp_path / "clip_sound.mkv", duration=3 / 12)
    out = tmp_path / "relit.mp4"
    assert main(["-q", "relight-video", str(with_sound), "--masks", str(masks), "--light", "sunset",
                 "--out", str(out)]) == 0
    assert len(list(read_video(out))) == 3
    with av.open(str(out)) as c:
        assert c.streams.audio and c.streams.audio[0].codec_context.name == "aac"
        assert sum(f.samples for f in c.decode(audio=0)) > 0


def test_frames_without_the_person_pass_through(tmp_path, masked_clip, capsys):
    from relightnet.io import write_image

    video, masks = masked_clip(tmp_path)
    write_image(masks / "001.png", np.zeros((64, 48, 3), np.uint8))  # the person is out of view in frame 1
    out = tmp_path / "relit.mkv"
    assert main(["relight-video", str(video), "--masks", str(masks), "--light", "sunset", "--out", str(out)]) == 0
    frames, src = list(read_video(out)), list(read_video(video))
    assert len(frames) == 3
    np.testing.assert_array_equal(frames[1], src[1])  # written unchanged (lossless mkv)
    assert not np.array_equal(frames[0], src[0])
    assert "1 frame(s) with an empty mask" in capsys.readouterr().err
    # Every mask empty: an error, and no output.
    for t in (0, 2):
        write_image(masks / f"{t:03d}.png", np.zeros((64, 48, 3), np.uint8))
    out2 = tmp_path / "none.mkv"
    assert main(["relight-video", str(video), "--masks", str(masks), "--light", "sunset", "--out", str(out2)]) == 1
    assert not out2.exists()


def test_one_mask_image_is_not_a_mask_sequence(tmp_path, masked_clip, capsys):
    video, masks = masked_clip(tmp_path)
    assert main(["relight-video", str(video), "--masks", str(masks / "000.png"), "--light", "sunset",
                 "--out", str(tmp_path / "x.mkv")]) == 1
    assert "a single image; expected a folder" in capsys.readouterr().err
    assert main(["relight-video", str(video), "--masks", str(masks), "--light", "sunset", "--turntable", "nan",
                 "--out", str(tmp_path / "x.mkv")]) == 1
    assert "turntable: expected degrees per second" in capsys.readouterr().err
    assert not (tmp_path / "x.mkv").exists()


def test_killed_relight_video_leaves_no_temp_file_after_a_rerun(tmp_path, masked_clip, kill_mid_run):
    from .conftest import temp_files

    video, masks = masked_clip(tmp_path, n=40)
    out = tmp_path / "out" / "relit.mkv"
    out.parent.mkdir()
    argv = ["relight-video", str(video), "--masks", str(masks), "--light", "sunset", "--out", str(out)]
    left = kill_mid_run(argv, out.parent)  # SIGKILL while the video is being written
    assert left and not out.exists()
    assert main(["-q", *argv]) == 0  # the rerun starts clean and removes the dead run's file
    assert temp_files(out.parent) == [] and len(list(read_video(out))) == 40


def test_relight_video_smoothing_is_a_method_name(tmp_path, masked_clip, capsys):
    """--smoothing takes the registry's causal names; a number (the former spelling) still works, with a note."""
    import pytest

    from relightnet.checks import InputError
    from relightnet.light import preset_light
    from relightnet.pipeline import make_predictor, relight_video

    video, masks = masked_clip(tmp_path)
    from relightnet.model import load_model

    outs = {}
    for name, extra in (("ema", ["--alpha", "0.3"]), ("pooled", []), ("auto", []), ("one-euro", []), ("none", [])):
        outs[name] = tmp_path / f"{name}.mkv"
        assert main(["-q", "relight-video", str(video), "--masks", str(masks), "--light", "sunset",
                     "--smoothing", name, *extra, "--out", str(outs[name])]) == 0
    # auto is pooled for a model that solves its light (the shipped hybrid), else ema at 0.3 (the default)
    same = "pooled" if load_model().config.light_mode in ("solve", "hybrid") else "ema"
    for a, b in zip(read_video(outs[same]), read_video(outs["auto"]), strict=True):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(SystemExit) as e:  # an offline method: refused by the parser
        main(["relight-video", str(video), "--masks", str(masks), "--light", "sunset", "--smoothing", "hermite",
              "--out", str(tmp_path / "x.mkv")])
    assert e.value.code == 2 and "hermite" in capsys.readouterr().err
    with pytest.raises(InputError, match="alpha"):
        relight_video(make_predictor("torch"), video, masks, preset_light("studio"), tmp_path / "y.mkv",
                      lights=VideoLightSettings(alpha=0))
    with pytest.raises(InputError, match="smoothing"):  # the EMA weight is alpha=, no longer a number here
        relight_video(make_predictor("torch"), video, masks, preset_light("studio"), tmp_path / "z.mkv",
                      lights=VideoLightSettings(smoothing=1.0), progress=False)


def test_a_clip_of_nobody_is_refused_after_its_first_seconds(tmp_path, masked_clip, capsys):
    from relightnet.pipeline.relight_video import NO_PERSON_S

    video, _ = masked_clip(tmp_path, n=40)  # 40 frames at 12 fps of a block on noise: nobody to segment
    out = tmp_path / "r.mp4"
    assert main(["-q", "relight-video", str(video), "--light", "studio", "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    last = int(NO_PERSON_S * 12) - 1
    assert len(err) == 1 and f"no person found in most of its first 2 s (frames 0-{last})" in err[0], err
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["clip.mkv", "masks"]


def test_a_few_false_positives_do_not_make_a_person():
    from relightnet.pipeline.relight_video import PERSON_SHARE, person_in_most

    nobody = [0.0] * 24
    for t in (0, 3, 4, 9):  # a segmentation's false positives: a few frames, even large ones
        nobody[t] = 0.2
    assert not person_in_most(nobody)
    assert not person_in_most([PERSON_SHARE / 2] * 24)  # specks below the share are nobody
    assert person_in_most([0.0] * 11 + [0.1] * 13)  # in view for most of the frames
    assert not person_in_most([0.0] * 12 + [0.1] * 12)  # half is not most
    assert person_in_most([PERSON_SHARE] * 3)


@pytest.mark.parametrize("clip", ["vfr", "late"])
def test_relight_video_keeps_the_frame_times_and_the_sync(tmp_path, clip):
    """A phone's variable frame rate (30 then 15 fps) and a video stream that starts 0.5 s after its sound
    come out as they went in: every frame against the sound within the writers' ms clocks."""
    from tests.io import timed_media as media

    times, clicks = {"vfr": (media.VFR_SHORT, [0.2]), "late": (media.LATE_SHORT, [0.5])}[clip]
    video = media.write_timed_clip(tmp_path / "phone.mp4", times, clicks)
    masks = media.write_masks(tmp_path / "masks", len(times))
    out = tmp_path / "relit.mp4"
    assert main(["-q", "relight-video", str(video), "--masks", str(masks), "--light", "sunset", "--out", str(out)]) == 0
    offsets = media.av_offsets(video, out)  # (T,) seconds, frame t later against the sound than in the source
    assert np.abs(offsets).max() <= 2e-3  # half a frame would be 17 ms (mp4 edit lists: a 1 ms clock)
    shown, heard = media.decoded_frame_times(out), media.click_times(out)
    np.testing.assert_allclose(np.diff(shown), np.diff(times), rtol=0, atol=1e-3)  # VFR stays VFR
    assert shown[0] - heard[0] == pytest.approx(times[0] - clicks[0], abs=2e-3)  # the late start kept


def test_the_carry_along_the_flow_steadies_a_still_person(tmp_path, masked_clip):
    """A still clip with sensor noise: each frame's prediction differs a little; carried along the flow,
    the relit person adds less change to the footage's own than relit from each frame alone."""
    from relightnet.io import VideoWriter
    from relightnet.pipeline.flicker import FlickerMeter

    video, masks = masked_clip(tmp_path)
    still, still_masks = tmp_path / "still.mkv", tmp_path / "still_masks.mkv"
    first = next(iter(read_video(video))).astype(np.float32)
    mask = next(iter(read_video(masks / "000.png")))
    rng = np.random.default_rng(0)
    with VideoWriter(still, fps=12) as w, VideoWriter(still_masks, fps=12, gray=True) as wm:
        for _ in range(4):
            w.write(np.clip(first + rng.normal(0, 3, first.shape), 0, 255).round().astype(np.uint8))
            wm.write(mask)
    added = {}
    for flag in ([], ["--no-carry"]):
        out = tmp_path / f"relit{len(flag)}.mkv"
        assert main(["-q", "relight-video", str(still), "--masks", str(still_masks), "--light", "sunset",
                     "--out", str(out), *flag]) == 0
        meter = FlickerMeter()
        for s, o in zip(read_video(still), read_video(out), strict=True):
            meter.update(s, o, mask[..., 0] > 127)
        added[bool(flag)] = meter.result()["added_flicker"] - 1
    assert added[False] < 0.7 * added[True], added


def test_hdr_is_kept_when_asked_and_refused_for_an_sdr_clip(tmp_path, masked_clip, capsys):
    import torch

    from relightnet.io.hdr_video import HdrFormat, hdr_format, read_linear_video
    from tests.io.hdr_media import hlg_codes as codes
    from tests.io.hdr_media import write_hlg_copy

    video, masks = masked_clip(tmp_path)
    out = tmp_path / "relit.mkv"
    assert main(["relight-video", str(video), "--masks", str(masks), "--light", "sunset", "--hdr",
                 "--out", str(out)]) == 1
    assert "not an HDR video" in capsys.readouterr().err and not out.exists()
    # the clip as HLG, its bright block 1.8x reference white: past the tone-mapping knee
    hlg = write_hlg_copy(video, tmp_path / "hlg.mkv", fps=12, gain=4)
    assert main(["-q", "relight-video", str(hlg), "--masks", str(masks), "--light", "sunset", "--hdr",
                 "--out", str(out)]) == 0
    assert hdr_format(out) == HdrFormat("hlg")
    src, relit = list(read_linear_video(hlg)), list(read_linear_video(out))
    assert len(relit) == 3 and float(src[0].amax()) > 1.5

    for t, (a, b) in enumerate(zip(src, relit, strict=True)):
        person = torch.zeros(a.shape[1:], dtype=torch.bool)
        person[8:56, 14 + t:30 + t] = True
        # outside the person (and a 3-pixel soft edge) the source's own HDR codes, to rounding (lossless ffv1)
        band = torch.nn.functional.max_pool2d(person[None, None].float(), 7, 1, 3)[0, 0].bool()
        assert (codes(a) - codes(b))[:, ~band].abs().max() <= 1
        assert (b - a)[:, person].abs().mean() > 0.05  # the person relit, in HDR
