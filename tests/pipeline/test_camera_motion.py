"""Camera motion: phase-correlation shifts (integer and sub-pixel), the person left out, a pan refused and a
static camera with a person walking through kept, early (the first frames) and over the plate's samples."""

import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.io import VideoWriter
from relightnet.pipeline.camera_motion import (
    MOTION_SHARE,
    THUMB_SIDE,
    check_fixed_camera,
    phase_shift,
    shifts_to_first,
    thumbnail,
)

H, W = 144, 192


def _texture(h: int, w: int, seed: int = 0, blur: float = 3.0) -> np.ndarray:
    """A (h, w) float texture in [0, 255]: white noise low-passed by a Gaussian of ``blur`` pixels."""
    rng = np.random.default_rng(seed)
    fy, fx = np.fft.fftfreq(h)[:, None], np.fft.fftfreq(w)[None, :]
    x = np.fft.ifft2(np.fft.fft2(rng.standard_normal((h, w))) * np.exp(-2 * np.pi**2 * blur**2 * (fy**2 + fx**2))).real
    return np.clip(128 + 60 * x / x.std(), 0, 255)


def _scene(n: int, pan: float = 0.0, pan_from: int = 0, follow: bool = False, seed: int = 1):
    """n (frame, mask) pairs of an (H, W) camera over a textured scene: the window slides ``pan`` px a frame
    to the right from frame ``pan_from`` on; a dark blob (the person) walks across the frame, or stays at
    its centre with ``follow`` (a camera that pans with the person)."""
    tex = _texture(H + 40, W + int(abs(pan) * n) + 40, seed)
    rgb = np.stack([tex, 0.8 * tex + 20, 255 - tex], -1)
    yy, xx = np.mgrid[:H, :W]
    out = []
    for t in range(n):
        x0 = 20 + int(round(pan * max(t - pan_from, 0)))
        f = rgb[20:20 + H, x0:x0 + W].copy()
        cx = W / 2 if follow else 20 + t * (W - 40) / max(n - 1, 1)
        m = ((xx - cx) / 14) ** 2 + ((yy - 80) / 45) ** 2 < 1
        f[m] = [40, 30, 35]
        out.append((f.round().astype(np.uint8), m))
    return out


def _thumbs(pairs):
    return [thumbnail(f, m) for f, m in pairs]


@pytest.mark.parametrize("shift", [(0, 0), (3, -7), (-12, 25), (1, 2), (6, -5), (-9, 17)])
def test_phase_shift_recovers_integer_and_subpixel_shifts(shift):
    """A texture sampled at 4× and block-averaged: a 4×-grid shift of (sy, sx) is a shift of (sy, sx) / 4."""
    big = _texture(4 * 120 + 80, 4 * 160 + 80, seed=3, blur=6.0)
    sy, sx = shift
    a = big[40:40 + 480, 40:40 + 640].reshape(120, 4, 160, 4).mean((1, 3))
    b = big[40 - sy:40 - sy + 480, 40 - sx:40 - sx + 640].reshape(120, 4, 160, 4).mean((1, 3))
    dy, dx = phase_shift(a, b)
    assert abs(dy - sy / 4) < 0.25 and abs(dx - sx / 4) < 0.25, (dy, dx, shift)
    dy, dx = phase_shift(big[40:520, 40:680], big[40 - sy:520 - sy, 40 - sx:680 - sx])  # whole pixels
    assert abs(dy - sy) < 0.25 and abs(dx - sx) < 0.25, (dy, dx, shift)


def test_phase_shift_leaves_the_invalid_pixels_out():
    """A static background with a bright textured patch (the person) moved by 20 px: the shift is the
    background's (0) with the patch left out."""
    bg, patch = _texture(H, W, seed=5), 255 - _texture(60, 40, seed=6)
    a, b = bg.copy(), bg.copy()
    a[40:100, 30:70], b[40:100, 50:90] = patch, patch
    valid = np.ones((H, W), bool)
    valid[35:105, 25:95] = False
    assert np.abs(phase_shift(a, b, valid)).max() < 0.1
    with pytest.raises(InputError, match="no valid pixel"):
        phase_shift(a, b, np.zeros((H, W), bool))
    with pytest.raises(InputError, match="one size"):
        phase_shift(a, b[:-1])


def test_thumbnail_is_at_most_the_side_and_grows_the_person():
    f = np.zeros((1080, 1920, 3), np.uint8)
    m = np.zeros((1080, 1920), bool)
    m[500, 900] = True
    t = thumbnail(f, m)
    assert t.scale == 8 and max(t.gray.shape) <= THUMB_SIDE and t.gray.shape == (135, 240)
    assert t.person.sum() == 9 and t.person[62, 112]  # the block (500 // 8, 900 // 8), grown by one
    small = thumbnail(np.zeros((H, W, 3), np.uint8))
    assert small.scale == 1 and small.gray.shape == (H, W) and not small.person.any()
    with pytest.raises(InputError, match="mask"):
        thumbnail(f, m[:-1])


def test_a_static_camera_with_a_person_walking_through_is_kept():
    pairs = _scene(30)
    shifts = check_fixed_camera("static.mp4", _thumbs(pairs), list(range(30)), W)
    assert np.abs(shifts).max() < 0.5, np.abs(shifts).max()


@pytest.mark.parametrize("follow", [False, True])
def test_a_pan_is_refused_naming_the_video_and_the_frames(follow):
    """A window sliding 1.5 px a frame over a textured scene, the person walking through it or followed by
    the camera (staying at the frame's centre): measured to a pixel and refused in one line."""
    pairs = _scene(30, pan=1.5, follow=follow)
    shifts = shifts_to_first(_thumbs(pairs))  # the window moves right: the scene moves left
    truth = np.array([-round(1.5 * t) for t in range(30)])
    assert np.abs(shifts[:, 1] - truth).max() < 0.75 and np.abs(shifts[:, 0]).max() < 0.5
    with pytest.raises(InputError) as e:
        check_fixed_camera("pan.mp4", _thumbs(pairs), list(range(0, 60, 2)), W)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("pan.mp4: the camera moves (44 px between frames 0 and 58)")
    assert msg.endswith("--replace-person needs a fixed camera")


def test_a_small_shake_is_within_the_threshold():
    """One pixel either way (0.5 % of the width) is kept; the threshold is 1 % of the width."""
    pairs = _scene(2, pan=1.0)
    check_fixed_camera("shake.mp4", _thumbs(pairs), [0, 1], W)
    with pytest.raises(InputError, match="camera moves"):
        check_fixed_camera("shake.mp4", _thumbs(pairs), [0, 1], W, share=0.4 * MOTION_SHARE)


def _write(folder, name, pairs):
    """``name.mkv`` (lossless) and ``name_masks.mkv`` (white = person) of (frame, mask) pairs."""
    video, masks = folder / f"{name}.mkv", folder / f"{name}_masks.mkv"
    with VideoWriter(video, fps=30) as v, VideoWriter(masks, fps=30) as vm:
        for f, m in pairs:
            v.write(f)
            vm.write(np.repeat(m[..., None] * np.uint8(255), 3, -1))
    return video, masks


@pytest.mark.slow
def test_replace_person_refuses_a_moving_camera_early_and_over_the_samples(tmp_path, anny_body, capsys):
    """The avatar job's early check (the first frames) refuses a pan at once, with one line naming the
    video; a camera that starts panning after them is refused by the plate's samples, before the median."""
    from relightnet.cli import main
    from relightnet.pipeline.clean_plate import check_camera_start, stand_in

    video, masks = _write(tmp_path, "pan", _scene(12, pan=2.0))
    with pytest.raises(InputError, match=r"pan\.mkv: the camera moves \(22 px between frames 0 and 11\)"):
        check_camera_start(video, masks)
    out = tmp_path / "a.mkv"
    rc = main(["-q", "avatar", "--target", str(video), "--target-masks", str(masks), "--light", "studio",
               "--replace-person", "--out", str(out)])
    assert rc == 1 and not out.exists() and not (tmp_path / "a.plate.png").exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pan.mkv: the camera moves (22 px between frames 0 and 11)" in err[0], err
    assert not (tmp_path / "a.lights.npz").exists()  # refused before anything was written
    late, late_masks = _write(tmp_path, "late", _scene(24, pan=3.0, pan_from=12))
    check_camera_start(late, late_masks, n_frames=12)  # still over its first 12 frames
    with pytest.raises(InputError, match=r"late\.mkv: the camera moves \(33 px between frames 0 and 23\)"):
        stand_in(late, tmp_path / "b.mkv", 24, anny_body, target_masks=late_masks)
    still, still_masks = _write(tmp_path, "still", _scene(12))
    check_camera_start(still, still_masks)
