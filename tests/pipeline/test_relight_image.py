import numpy as np
import pytest
import torch

from relightnet.cli import main
from relightnet.data import SynthConfig, generate_sample
from relightnet.io import read_image, write_image
from relightnet.light import load_light, preset_light
from relightnet.model import load_model
from relightnet.pipeline import relight_image
from relightnet.segment.matte import band_radius, border_band

pytestmark = pytest.mark.slow  # the CNN on real photos, relighting, the CLI; 8-17 s each on a loaded machine


@pytest.fixture(scope="module")
def photo(anny_body):
    a = generate_sample(SynthConfig(res=96, n_dirs=16), "test", 1, body=anny_body).arrays
    # Put the person into a bigger, non-square frame with a textured background.
    img = np.full((120, 150, 3), 90, np.uint8)
    img[::7] = 200
    mask = np.zeros((120, 150), np.float32)
    img[10:106, 30:126] = np.where(a["mask"][..., None] > 0.5, a["image_srgb"], img[10:106, 30:126])
    mask[10:106, 30:126] = a["mask"]
    return torch.from_numpy(img).permute(2, 0, 1), torch.from_numpy(mask)


def test_relight_keeps_background_and_size(photo):
    img, mask = photo
    res = relight_image(load_model(), img, preset_light("sunset"), mask)
    assert res.image.shape == (120, 150, 3)
    outside = mask < 0.5
    orig = img.permute(1, 2, 0).float() / 255
    band = border_band(mask, band_radius(120, 150))  # the soft edge changes its band only
    torch.testing.assert_close(res.image[outside & ~band], orig[outside & ~band])
    hard = relight_image(load_model(), img, preset_light("sunset"), mask, soft_edges=False).image
    torch.testing.assert_close(hard[outside], orig[outside])
    torch.testing.assert_close(res.image[~band], hard[~band])
    assert (res.image[~outside] - orig[~outside]).abs().mean() > 0.005  # the person changed
    # Exposure is kept: the relit person is about as bright as in the photo.
    assert 0.3 < float(res.image[~outside].mean() / orig[~outside].mean()) < 3.0


def test_cli_relight_image_and_errors(photo, tmp_path, capsys):
    img, mask = photo
    write_image(tmp_path / "p.png", img.permute(1, 2, 0))
    write_image(tmp_path / "m.png", mask[..., None].expand(-1, -1, 3), srgb=False)
    out = tmp_path / "r.png"
    assert main(["-q", "relight-image", str(tmp_path / "p.png"), "--mask", str(tmp_path / "m.png"), "--light",
                 "studio", "--out", str(out), "--save-maps", str(tmp_path / "maps")]) == 0
    assert read_image(out).shape == (120, 150, 3)
    assert load_light(tmp_path / "maps" / "light_estimated.npz").shape == (9, 3)
    write_image(tmp_path / "small.png", np.zeros((10, 10, 3), np.uint8))
    assert main(["relight-image", str(tmp_path / "p.png"), "--mask", str(tmp_path / "small.png"), "--light",
                 "studio", "--out", str(tmp_path / "x.png")]) == 1
    assert "differs from the image" in capsys.readouterr().err
    write_image(tmp_path / "empty.png", np.zeros((120, 150, 3), np.uint8))
    assert main(["relight-image", str(tmp_path / "p.png"), "--mask", str(tmp_path / "empty.png"), "--light",
                 "studio", "--out", str(tmp_path / "x.png")]) == 1
    assert "empty mask" in capsys.readouterr().err
    bad = tmp_path / "bad.npy"
    np.save(bad, np.full((9, 3), np.nan, np.float32))
    assert main(["relight-image", str(tmp_path / "p.png"), "--mask", str(tmp_path / "m.png"), "--light",
                 str(bad), "--out", str(tmp_path / "x.png")]) == 1
    assert "NaN" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


def test_cli_soft_edges_change_the_border_band_only(photo, tmp_path):
    img, mask = photo
    write_image(tmp_path / "p.png", img.permute(1, 2, 0))
    write_image(tmp_path / "m.png", mask[..., None].expand(-1, -1, 3), srgb=False)
    args = ["-q", "relight-image", str(tmp_path / "p.png"), "--mask", str(tmp_path / "m.png"), "--light", "sunset"]
    assert main(args + ["--out", str(tmp_path / "soft.png")]) == 0
    assert main(args + ["--out", str(tmp_path / "hard.png"), "--hard-edges"]) == 0
    soft, hard = read_image(tmp_path / "soft.png"), read_image(tmp_path / "hard.png")
    band = border_band(mask, band_radius(120, 150)).numpy()
    assert np.array_equal(soft[~band], hard[~band])
    assert not np.array_equal(soft[band], hard[band])
    # the same relight as JPEG and WebP: the picture within a lossy codec's error, the quality applied
    for name in ("r.jpg", "r.webp", "low.jpg"):
        q = "30" if name.startswith("low") else "95"
        assert main(args + ["--out", str(tmp_path / name), "--quality", q]) == 0
        assert np.abs(read_image(tmp_path / name).numpy() - soft.numpy()).mean() < (0.05 if q == "30" else 0.02)
    assert (tmp_path / "low.jpg").stat().st_size < (tmp_path / "r.jpg").stat().st_size


def test_relighting_with_the_estimated_light_gives_the_photo_back(photo):
    img, mask = photo
    model = load_model()
    est = relight_image(model, img, preset_light("studio"), mask).prediction.light[0]
    orig = img.permute(1, 2, 0).float() / 255
    inside = mask > 0.5
    # The photo's own albedo (photo / predicted shading) under the light it was seen in is the
    # photo, detail included, wherever the shading is strong enough to carry its own colour
    # (model.photo_albedo: elsewhere the divisor's colour is bounded); the CNN's albedo is not.
    from relightnet.color import LUMA
    from relightnet.model.photo_albedo import CHROMA_FULL, CHROMA_RANGE

    same = relight_image(model, img, est, mask, keep_exposure=False)
    shading = same.prediction.shading()[0]
    y = torch.einsum("chw,c->hw", shading, torch.tensor(LUMA))
    mean = (shading * inside).sum((1, 2)) / inside.sum()
    tint = mean / float(mean @ torch.tensor(LUMA))
    local = shading / y.clamp_min(1e-8)
    confident = inside & (y >= CHROMA_FULL * float(mean @ torch.tensor(LUMA)))
    confident &= ((local / tint[:, None, None]).log().abs() < CHROMA_RANGE).all(0)
    assert float(confident.sum()) > 0.5 * float(inside.sum())
    err = (same.image - orig).abs()
    assert float(err[confident].mean()) < 1e-4
    assert float(err[inside].mean()) < 0.01
    cnn = relight_image(model, img, est, mask, keep_exposure=False, detail=False)
    assert float((cnn.image[inside] - orig[inside]).abs().mean()) > 0.01
    assert same.albedo.shape == (3, 120, 150)


def test_cutouts_stay_cutouts_and_odd_lights_are_flagged(photo, tmp_path, capsys):
    import av

    from relightnet.io.image import read_alpha

    img, mask = photo
    rgba = np.concatenate([img.permute(1, 2, 0).numpy(), (mask.numpy()[..., None] * 255).astype(np.uint8)], -1)
    cut = tmp_path / "cut.png"
    from relightnet.io.image import _encode

    cut.write_bytes(_encode("png", av.VideoFrame.from_ndarray(np.ascontiguousarray(rgba), format="rgba")))
    out = tmp_path / "r.png"
    assert main(["relight-image", str(cut), "--light", "sunset", "--out", str(out)]) == 0
    assert "alpha channel of" in capsys.readouterr().err  # the cut-out's alpha was the mask
    torch.testing.assert_close(read_alpha(out), read_alpha(cut))  # ... and the output keeps it
    assert main(["relight-image", str(cut), "--light", "sunset", "--out", str(tmp_path / "r.jpg")]) == 1
    assert "a JPEG has none" in capsys.readouterr().err and not (tmp_path / "r.jpg").exists()
    assert main(["-q", "relight-image", str(cut), "--light", "sunset", "--out", str(tmp_path / "r.webp")]) == 0
    torch.testing.assert_close(read_alpha(tmp_path / "r.webp"), read_alpha(cut), atol=2 / 255, rtol=0)
    # A light negative nearly everywhere is refused before any work; one from behind the person
    # lights too little of them (a warning); one of a higher order than the model's is truncated.
    neg = tmp_path / "neg.npy"
    np.save(neg, -np.ones((9, 3), np.float32))
    assert main(["relight-image", str(cut), "--light", str(neg), "--out", str(tmp_path / "n.png")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "neg.npy: its R irradiance is negative over" in err[0], err
    assert not (tmp_path / "n.png").exists()
    back = np.zeros((9, 3), np.float32)
    back[0], back[3] = 0.2, -1.0  # ambient and a strong dipole away from the camera
    np.save(neg, back)  # negative over ~38% of the sphere: passes with a warning, and lights little of the person
    assert main(["relight-image", str(cut), "--light", str(neg), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "irradiance is negative over" in err and "is it a valid SH light" in err
    from relightnet.sh import save_light

    hi = save_light(tmp_path / "hi.npz", torch.cat([preset_light("studio"), torch.zeros(7, 3)]))
    assert main(["relight-image", str(cut), "--light", str(hi), "--out", str(out)]) == 0
    assert "order 3 truncated to the model's order 2" in capsys.readouterr().err


def test_relight_is_the_shading_kernel_and_backends_agree(photo):
    """The photo relight = A ⊙ (T · L) (render.shade) over the photo; relight-image runs on either backend."""
    from relightnet.color import srgb_to_linear
    from relightnet.model import photo_albedo, shading_map
    from relightnet.pipeline import make_predictor, relight_over_photo

    img, mask = photo
    predict = make_predictor("torch")
    crop = predict.crop(img, mask)
    pred = crop.pasted()
    light = preset_light("sunset")
    image = img.float()[None] / 255
    r = relight_over_photo(crop, img, light, keep_exposure=False, keep_albedo=True, composite=False)
    albedo = photo_albedo(srgb_to_linear(image), pred)
    torch.testing.assert_close(r.albedo, albedo[0], rtol=1e-4, atol=1e-5)
    torch.testing.assert_close(r.image, (albedo * shading_map(pred.transport, light))[0].permute(1, 2, 0),
                               rtol=1e-4, atol=1e-5)
    out = relight_over_photo(crop, img, light, keep_exposure=False).image
    assert out.shape == (120, 150, 3)
    outside = mask < 0.5
    torch.testing.assert_close(out[outside], image[0].permute(1, 2, 0)[outside])
    # The predictor's working size is the checkpoint's (the shipped model was trained on 128² crops).
    assert predict.size == predict.model.config.input_size == 128
    res = relight_image(predict, img, light, mask)
    torch.testing.assert_close(res.image, relight_image(load_model(), img, light, mask).image, rtol=1e-4, atol=1e-4)
