"""The clean plate: temporal median of uncovered samples, push-pull inpainting, placement, --replace-person."""

import math

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.cli import main
from relightnet.io import VideoWriter, read_video
from relightnet.light import ambient_light
from relightnet.pipeline.clean_plate import (
    WARN_SHARE,
    Placement,
    clean_plate,
    dilate_masks,
    masked_median,
    person_placement,
    placed_camera,
    plate_psnr,
    push_pull_fill,
    sample_indices,
    stand_in,
)
from relightnet.pipeline.walk_target import walking_target

SIZE, N = (144, 192), 20


@pytest.fixture(scope="module")
def walk(tmp_path_factory, anny_body):
    """A generated target (mp4, lossy as a user's video): Anny walking across a known textured background."""
    return walking_target(tmp_path_factory.mktemp("walk"), size=SIZE, n_frames=N, suffix=".mp4", body=anny_body)


def test_sample_indices_spread_and_bounded():
    assert sample_indices(5, 10) == [0, 1, 2, 3, 4]
    idx = sample_indices(100, 8)
    assert len(idx) == 8 and idx[0] == 0 and idx[-1] == 99 and idx == sorted(set(idx))
    with pytest.raises(InputError, match="n_frames"):
        sample_indices(0, 4)


def test_masked_median_uses_only_uncovered_samples():
    frames = torch.tensor([10, 200, 30, 40, 250], dtype=torch.uint8).view(5, 1, 1, 1).expand(5, 2, 3, 3).clone()
    covered = torch.zeros(5, 2, 3, dtype=torch.bool)
    covered[[1, 4]] = True  # the person (200, 250) in frames 1 and 4
    covered[:, 1, 2] = True  # one pixel never uncovered
    med, count = masked_median(frames, covered)
    assert torch.equal(med[0, 0], torch.full((3,), 30.0))  # median of 10, 30, 40
    assert int(count[0, 0]) == 3 and int(count[1, 2]) == 0 and torch.isnan(med[1, 2]).all()


def test_dilate_grows_by_the_margin():
    m = torch.zeros(1, 9, 9, dtype=torch.bool)
    m[0, 4, 4] = True
    d = dilate_masks(m, 2)
    assert int(d.sum()) == 25 and bool(d[0, 2, 2]) and not bool(d[0, 1, 4])


def test_push_pull_reproduces_linear_ramps_and_keeps_known_pixels():
    y, x = torch.meshgrid(torch.arange(40.0), torch.arange(50.0), indexing="ij")
    img = torch.stack([x, y, x + y], -1)
    known = torch.ones(40, 50, dtype=torch.bool)
    known[10:22, 15:30] = False
    filled = push_pull_fill(torch.where(known[..., None], img, torch.full((), 999.0)), known)
    assert torch.equal(filled[known], img[known])
    hole = filled[~known]
    assert float(hole.min()) >= 0 and float(hole.max()) <= float(img.max())  # a blend of the surroundings
    # Smooth: neighbouring hole pixels differ by little more than the ramp's own step (1 per pixel).
    assert float((filled[10:22, 16:30] - filled[10:22, 15:29]).abs().max()) < 3.0
    with pytest.raises(InputError, match="no known pixel"):
        push_pull_fill(img, torch.zeros(40, 50, dtype=torch.bool))


def test_plate_of_a_still_person_flags_the_area_never_uncovered():
    rng = np.random.default_rng(0)
    bg = rng.integers(0, 255, (40, 60, 3), dtype=np.uint8)
    mask = np.zeros((40, 60), bool)
    mask[10:30, 20:30] = True
    frames = [(np.where(mask[..., None], 0, bg).astype(np.uint8), mask) for _ in range(6)]
    cp = clean_plate(iter(frames), 6, margin=1)
    grown = dilate_masks(torch.from_numpy(mask)[None], 1)[0].numpy()
    assert np.array_equal(cp.flagged, grown) and np.array_equal(cp.covered, grown)
    assert cp.inpainted_share == 1.0
    assert np.array_equal(cp.plate[~grown], bg[~grown])


def test_placed_camera_puts_the_feet_and_height_where_the_person_stood():
    where = Placement((70.0, 120.0), 90.0)
    cam = placed_camera((144, 192), where, 1.7)
    pts = torch.tensor([[0.0, 0.0, 0.0], [0.0, 1.7, 0.0]])
    ndc = cam.transform(pts[None])[0]
    px = (ndc[:, 0] / ndc[:, 3] + 1) / 2 * 192, (1 - ndc[:, 1] / ndc[:, 3]) / 2 * 144
    assert abs(float(px[0][0]) - 70) < 0.5 and abs(float(px[1][0]) - 120) < 0.5
    assert abs(float(px[1][0] - px[1][1]) - 90) < 0.5
    assert torch.allclose(cam.R, torch.eye(3).expand_as(cam.R), atol=1e-6)  # same light frame as the default


def test_person_placement_is_the_median_of_the_masks():
    ms = []
    for x0 in (10, 20, 30):
        m = np.zeros((50, 60), bool)
        m[5:45, x0:x0 + 8] = True
        ms.append(m)
    ms.append(np.zeros((50, 60), bool))  # an empty mask does not count
    p = person_placement(ms)
    assert p.height == 40 and p.feet[1] == 45 and abs(p.feet[0] - 24.0) < 1e-6  # columns 20..27, centres at +0.5
    assert person_placement([np.zeros((5, 5), bool)]) is None


@pytest.mark.slow
def test_plate_of_a_walking_person_is_within_30_db_of_the_true_background(walk, anny_body, tmp_path):
    """Target: masks from the person segmentation, PSNR over the pixels the person covered and
    later uncovered (the inpainted ones excluded and reported)."""
    cp, cam, _ = stand_in(walk.video, tmp_path / "o.mp4", N, anny_body)
    region = walk.ever & ~walk.always & ~cp.flagged
    assert region.sum() > 0.3 * walk.ever.sum()
    psnr = plate_psnr(cp.plate, walk.background, region)
    assert psnr >= 30.0, psnr
    assert cp.inpainted_share < WARN_SHARE
    assert (tmp_path / "o.plate.png").is_file()
    assert math.isfinite(psnr)


def _eye(cam) -> torch.Tensor:
    V = cam.view[0].double()
    return -(V[:3, :3].T @ V[:3, 3])


def test_the_avatar_follows_the_walking_person(walk, anny_body, tmp_path):
    """With masks from the person segmentation, the avatar's feet follow the person's true path.

    Compared relative to each camera (the target's default camera, the avatar's placed one), which is what
    puts the avatar where the person is in the image. Bounds at 192×144 (f ≈ 228 px, 3 m away: 1 px ≈
    1.3 cm across): across the frame within 4 px (5 cm) on average; in depth, which comes from the height
    in pixels (131 px), within 3 % of the distance (10 cm), over the frames that show the whole person."""
    from relightnet.io import read_video
    from relightnet.pipeline.clean_plate import person_box
    from relightnet.raster import default_camera

    _, cam, off = stand_in(walk.video, tmp_path / "o.mp4", N, anny_body)
    truth = torch.as_tensor(walk.path, dtype=torch.float64)
    truth[:, 1] = 0.0  # the feet on the ground
    est = off.double() - _eye(cam)
    rel = truth - _eye(default_camera(SIZE))
    whole = np.array([b is not None and not np.isnan(b[0]) for b in (person_box(m[..., 0] > 127)
                                                                      for m in read_video(walk.masks))])
    assert whole.sum() >= 8
    err = (est - rel).abs().numpy()[whole]
    assert err[:, 0].mean() < 0.05 and err[:, 2].mean() < 0.1 and err[:, 1].mean() < 0.05, err.mean(0)
    # The person crosses the frame: a fixed place (the median's) would be off by a quarter of the crossing.
    fixed = (torch.zeros(3, dtype=torch.float64) - _eye(cam) - rel).abs().numpy()[whole]
    assert fixed[:, 0].mean() > 5 * err[:, 0].mean()


@pytest.mark.slow
def test_replace_person_end_to_end_and_refusals(walk, tmp_path, capsys):
    out = tmp_path / "a.mkv"
    args = ["avatar", "--target", str(walk.video), "--n-dirs", "8", "--out", str(out)]
    light = tmp_path / "l.npz"
    from relightnet.sh import save_light

    save_light(light, ambient_light(0.6))
    still = tmp_path / "still.mp4"  # a person who never moves: the warning with the share
    first = list(read_video(walk.video))[N // 2]
    person = list(read_video(walk.masks))[N // 2][..., 0] > 127
    with VideoWriter(still, fps=30) as w:
        for _ in range(4):
            w.write(first)
    capsys.readouterr()
    assert main(["-q", *args[:2], str(still), *args[3:], "--light", str(light), "--replace-person"]) == 0
    warn = [line for line in capsys.readouterr().err.splitlines() if "inpainted" in line]
    assert len(warn) == 1 and "WARNING" in warn[0] and "% of the person's area" in warn[0], warn
    frames = list(read_video(out))
    assert len(frames) == 4 and (tmp_path / "a.plate.png").is_file()
    # The avatar stands where the person stood: the pixels it changes span the person's rows and columns.
    from relightnet.io import read_image

    plate = (read_image(tmp_path / "a.plate.png") * 255).round().numpy()
    changed = np.abs(frames[0].astype(float) - plate).max(-1) > 40
    rows, cols = np.nonzero(changed)
    prow, pcol = np.nonzero(person)
    h = prow.max() - prow.min()
    assert abs(rows.max() - prow.max()) < 0.08 * h and abs((rows.max() - rows.min()) - h) < 0.12 * h
    assert abs(np.median(cols) - np.median(pcol)) < 0.15 * h
    out.unlink()
    for extra, text in ((["--plate", str(still)], "--replace-person"), (["--outfit", "nope"], "--outfit nope"),
                        (["--mask-source", "head"], "--replace-person")):
        assert main([*args, "--light", str(light), "--replace-person", *extra]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and text in err[0], err
        assert not out.exists()
