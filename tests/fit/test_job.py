"""The fit's outputs over a video: the preview and the fitted masks, frame for frame."""

import numpy as np
import torch

from relightnet.fit import FitResult, default_intrinsics
from relightnet.fit.body_model import FIT_BONES
from relightnet.fit.job import write_fit_masks, write_preview
from relightnet.io import VideoWriter, read_video, video_info


def test_preview_and_masks_of_a_video(tmp_path, fit_body):
    T, size = 3, (64, 48)
    src = tmp_path / "src.mp4"
    with VideoWriter(src, fps=10) as w:
        for _ in range(T):
            w.write(np.full((*size, 3), 90, np.uint8))
    trans = torch.tensor([0.0, -0.9, -2.2]).expand(T, 3).clone()
    res = FitResult(torch.zeros(T, len(FIT_BONES), 3), trans, fit_body.body.phenotype_tensor(None)[0],
                    default_intrinsics(size, 60.0), size, torch.zeros(T), torch.zeros(T, dtype=torch.bool), 0.0)
    write_preview(tmp_path / "p.mp4", src, res, fit_body, 10.0)
    write_fit_masks(tmp_path / "m.mkv", res, fit_body, 10.0)
    assert video_info(tmp_path / "p.mp4").n_frames == T
    frames = np.stack(list(read_video(tmp_path / "p.mp4"))).astype(int)
    masks = np.stack(list(read_video(tmp_path / "m.mkv")))[..., 0] > 127
    assert masks.shape == (T, *size) and 0.03 < masks.mean() < 0.6
    # the overlay changes the frame where the body is, and only there
    changed = np.abs(frames - 90).max(-1) > 20
    assert changed[masks].mean() > 0.9 and changed[~masks].mean() < 0.05


def test_frames_are_rasterized_a_few_at_a_time(fit_body):
    """8 frames of a small video together, one frame at a time from 2 MP up; any chunking gives the same masks."""
    from relightnet.fit.preview import CHUNK_PIXELS, chunk_frames, fit_silhouettes

    assert chunk_frames((192, 192)) == 8 and chunk_frames((1080, 1920)) == 1 and chunk_frames((3120, 4000)) == 1
    assert chunk_frames((512, 512)) * 512 * 512 <= CHUNK_PIXELS
    T, size = 5, (40, 32)
    trans = torch.tensor([0.0, -0.9, -2.2]).expand(T, 3).clone()
    trans[:, 0] = torch.linspace(-0.3, 0.3, T)
    res = FitResult(torch.zeros(T, len(FIT_BONES), 3), trans, fit_body.body.phenotype_tensor(None)[0],
                    default_intrinsics(size, 60.0), size, torch.zeros(T), torch.zeros(T, dtype=torch.bool), 0.0)
    whole = fit_silhouettes(res, fit_body)
    assert whole.shape == (T, *size) and whole.sum() > 0
    assert torch.equal(fit_silhouettes(res, fit_body, chunk=2), whole)
    assert torch.equal(fit_silhouettes(res, fit_body, chunk=1, start=1, stop=4), whole[1:4])


def test_overlay_blends_the_covered_pixels_as_the_whole_image_formula_did(fit_body):
    """The overlay is blended at the covered pixels only; every pixel equals the old whole-image formula's
    (frames × (1 − a) + colour × a, clamped, a = opacity × coverage), bit for bit, also for strided frames."""
    from relightnet.fit.preview import _frags, fit_silhouettes, overlay_frames
    from relightnet.raster import interpolate

    T, size = 2, (40, 32)
    trans = torch.tensor([[0.1, -0.9, -2.2], [-0.1, -0.9, -2.4]])
    res = FitResult(torch.zeros(T, len(FIT_BONES), 3), trans, fit_body.body.phenotype_tensor(None)[0],
                    default_intrinsics(size, 60.0), size, torch.zeros(T), torch.zeros(T, dtype=torch.bool), 0.0)
    g = torch.Generator().manual_seed(0)
    frames = torch.randint(0, 256, (T, *size, 3), dtype=torch.uint8, generator=g).permute(0, 3, 1, 2).float() / 255
    out, fr = _frags(res, fit_body, 0, T)
    n = interpolate(out.normals, fr, out.faces)
    colour = torch.tensor([0.55, 0.75, 1.0])[None, :, None, None] * (0.25 + 0.75 * n[..., 2].clamp(0, 1))[:, None]
    a = 0.6 * fr.mask.float()[:, None]
    old = (frames * (1 - a) + colour * a).clamp(0, 1)
    new = overlay_frames(frames, res, fit_body)
    assert torch.equal(new, old) and fit_silhouettes(res, fit_body).mean() > 0.05
