"""The real-photo checks (``evaluate photos``): the side-contrast and round-trip math on cases with a known
answer, a folder with photos with and without a person and an unreadable one, the command's table and errors.

The photos are made here: scikit-image's astronaut (a real photo of a person), a flat gray picture (no person)
and a file that is not an image."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.cli import main
from relightnet.color import linear_to_srgb, srgb_to_linear
from relightnet.io import write_image
from relightnet.light import render_sphere, side_light
from relightnet.light.visualize import sphere_normals
from relightnet.pipeline.photo_checks import (
    SIDE_LEFT,
    check_lights,
    check_photo,
    format_photo_report,
    photo_checks,
    side_contrast,
    side_means,
)
from relightnet.sh import scale_invariant_light_error


@pytest.fixture(scope="module")
def person_models():
    from relightnet.segment import PersonModels

    return PersonModels(threads=1)


@pytest.fixture(scope="module")
def photos(tmp_path_factory):
    """A folder: the astronaut (512²), a flat gray picture (no person), a file that is not an image."""
    from skimage import data

    d = tmp_path_factory.mktemp("photos")
    write_image(d / "astronaut.png", torch.from_numpy(data.astronaut()), srgb=False)
    write_image(d / "gray.png", torch.full((96, 64, 3), 128, dtype=torch.uint8), srgb=False)
    (d / "junk.png").write_bytes(b"not an image")
    (d / "notes.txt").write_text("not a photo")
    return d


def unchanged(image, mask, light):
    """A relighter that changes nothing."""
    return image


def ambient_estimate(image, mask):
    """An estimator that always answers a direction-less white light."""
    light = torch.zeros(9, 3)
    light[0] = 1.0
    return light


def test_the_check_lights_are_the_side_lights_from_above_and_presets():
    torch.testing.assert_close(check_lights()["left"], side_light(SIDE_LEFT))
    lights = check_lights()
    assert list(lights)[:3] == ["left", "right", "above"] and all(v.shape == (9, 3) for v in lights.values())


def test_the_left_light_lights_the_image_left_of_a_lambertian_sphere():
    """d_left = (0.5, -0.85, 0.2): y_light is the image's right, so it comes from the image's left."""
    size = 128
    _, disc = sphere_normals(size)

    def lit(name):
        return linear_to_srgb((0.5 * render_sphere(check_lights()[name], size)).clamp(0, 1)).permute(2, 0, 1)

    left, right, split = side_means(lit("left"), disc.float())
    assert split == pytest.approx(size / 2) and left > 2 * right
    res = side_contrast(lit("left"), lit("right"), disc.float())
    assert res["ratio_under_left"] > 1 > res["ratio_under_right"]
    assert res["side_contrast"] == pytest.approx(12.7, abs=0.05)  # the ideal relighter is far above the target 4


def test_side_means_split_at_the_mask_centroid_in_linear_luminance():
    image = torch.zeros(3, 4, 10)
    mask = torch.zeros(4, 10)
    mask[:, 2:6] = 1  # columns 2..5 on every row ...
    mask[0, 6:10] = 1  # ... and 6..9 on the first: centroid (16·4 + 4·8) / 20 = 4.8, box middle 6
    image[:, :, :5] = 0.5  # gray on columns 0..4 (left of 4.8)
    image[0, :, 5:] = 1.0  # pure red on 5..9
    left, right, split = side_means(image, mask)
    assert split == pytest.approx(4.8)
    assert left == pytest.approx(float(srgb_to_linear(torch.tensor(0.5))), rel=1e-6)  # gray: luminance = value
    assert right == pytest.approx(0.2126, rel=1e-6)  # Rec. 709 red weight
    with pytest.raises(InputError, match="mask: empty"):
        side_means(image, torch.zeros(4, 10))
    with pytest.raises(InputError, match="mask"):
        side_means(image, torch.ones(4, 9))


def test_a_relighter_that_changes_nothing_gives_contrast_one_and_the_baseline():
    image = torch.rand(3, 20, 16, generator=torch.Generator().manual_seed(0))
    mask = torch.zeros(20, 16)
    mask[3:17, 4:12] = 1
    res = check_photo(image, mask, unchanged, ambient_estimate)
    assert res["side_contrast"] == pytest.approx(1.0, abs=1e-12)
    assert res["round_trip"] == res["baseline"]
    for name, light in check_lights().items():  # the error of a direction-less light against each light
        expected = float(scale_invariant_light_error(ambient_estimate(None, None).double(), light.double()))
        assert res["round_trip"][name] == pytest.approx(expected)
    assert res["round_trip_median"] == pytest.approx(float(np.median(list(res["round_trip"].values()))))
    with pytest.raises(InputError, match="needs the lights right"):
        check_photo(image, mask, unchanged, ambient_estimate, lights={"left": side_light(SIDE_LEFT)})


def test_a_folder_flags_photos_without_a_person_and_unreadable_files(photos, person_models):
    res = photo_checks(None, photos, max_height=256, person_models=person_models, relight=unchanged,
                       estimate=ambient_estimate)
    rows = {r["photo"]: r for r in res["photos"]}
    assert list(rows) == ["astronaut.png", "gray.png", "junk.png"]  # notes.txt is not a photo
    astro = rows["astronaut.png"]
    assert astro["status"] == "ok" and astro["size"] == [256, 256] and astro["original_size"] == [512, 512]
    assert 0.05 < astro["person"] < 0.9 and astro["side_contrast"] == pytest.approx(1.0)
    assert rows["gray.png"]["status"] == "no person" and "no person found" in rows["gray.png"]["note"]
    assert rows["junk.png"]["status"] == "unreadable" and "junk.png" in rows["junk.png"]["note"]
    m = res["median"]
    assert (m["n_photos"], m["n_checked"]) == (3, 1) and m["side_contrast"] == pytest.approx(1.0)
    assert m["round_trip"] == m["baseline"] == pytest.approx(astro["round_trip_median"])
    text = format_photo_report(res, "identity")
    assert "| gray.png | 64×96 | – |" in text and "shrunk from 512×512" in text and "| **median** (1 of 3" in text


def test_a_folder_without_readable_photos_or_people_is_refused(tmp_path, person_models):
    def check(folder):
        return photo_checks(None, folder, person_models=person_models, relight=unchanged, estimate=ambient_estimate)

    with pytest.raises(InputError, match="no such folder"):
        check(tmp_path / "missing")
    (tmp_path / "a.txt").write_text("x")
    with pytest.raises(InputError, match=r"no photos \(.png, .jpg, .jpeg, .webp"):
        check(tmp_path)
    (tmp_path / "b.jpg").write_bytes(b"junk")
    with pytest.raises(InputError, match=f"{tmp_path}: no readable photos"):
        check(tmp_path)
    write_image(tmp_path / "c.png", torch.full((64, 48, 3), 0.5))
    with pytest.raises(InputError, match="no person found in any photo"):
        check(tmp_path)


@pytest.mark.slow
def test_evaluate_photos_prints_and_writes_the_table(photos, tmp_path, capsys):
    out = tmp_path / "rep"
    assert main(["-q", "evaluate", "photos", str(photos), "--out", str(out)]) == 0
    table = capsys.readouterr().out
    assert "| astronaut.png | 512×512 |" in table and "| **median** (1 of 3 photos" in table
    assert sorted(p.name for p in out.iterdir()) == ["photo_checks.json", "photo_checks.md"]
    res = json.loads((out / "photo_checks.json").read_text())
    astro = res["photos"][0]
    assert res["model"] == "shipped model" and res["lights"] == list(check_lights())
    assert astro["side_contrast"] > 1.2  # the shipped model lights the side the light comes from
    assert all(0 <= v <= 1 for v in astro["round_trip"].values()) and math.isfinite(res["median"]["round_trip"])
    assert table.strip() in (out / "photo_checks.md").read_text()


def test_evaluate_photos_errors_are_one_line_and_write_nothing(tmp_path, capsys):
    out = tmp_path / "new" / "rep"
    for argv, message in [
        ([str(tmp_path / "missing")], "missing: no such folder"),
        ([str(tmp_path)], "no photos"),
    ]:
        assert main(["evaluate", "photos", *argv, "--out", str(out)]) == 1
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
    for argv in (["--data", str(tmp_path)], ["--split", "val"], ["--clips", str(tmp_path)]):
        with pytest.raises(SystemExit):  # the options of the other reports are not the photo checks'
            main(["evaluate", "photos", str(tmp_path), *argv, "--out", str(out)])
        assert f"unrecognized arguments: {argv[0]}" in capsys.readouterr().err
    (tmp_path / "x.jpg").write_bytes(b"junk")
    assert main(["evaluate", "photos", str(tmp_path), "--out", str(out)]) == 1
    assert f"{tmp_path}: no readable photos" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()
