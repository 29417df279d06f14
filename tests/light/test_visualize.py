"""Lit-sphere rendering, previews and preset pictures."""

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.io import read_image
from relightnet.light import (
    ambient_light,
    directional_light,
    light_preview,
    preset_names,
    render_presets,
    render_sphere,
)
from relightnet.light.visualize import sphere_normals

S = 64


def test_sphere_normals_front_and_back():
    n, mask = sphere_normals(S)
    assert n.shape == (S, S, 3) and mask.shape == (S, S)
    torch.testing.assert_close(n[mask].norm(dim=-1), torch.ones(int(mask.sum())))
    assert (n[mask][:, 2] > 0).all() and (n[~mask] == 0).all()
    assert n[S // 8, S // 2, 1] > 0.7 and n[S - 1 - S // 8, S // 2, 1] < -0.7  # top is up (+y)
    assert n[S // 2, S - 1 - S // 8, 0] > 0.7  # image right is +x
    nb, mb = sphere_normals(S, "back")
    assert (mb == mask).all() and (nb[mask][:, 2] < 0).all()
    assert nb[S // 2, S - 1 - S // 8, 0] < -0.7  # seen from behind, image right is -x


def test_ambient_sphere_is_uniform_albedo_one():
    img = render_sphere(ambient_light([0.2, 0.4, 0.8]), S)
    _, mask = sphere_normals(S)
    torch.testing.assert_close(img[mask], torch.tensor([0.2, 0.4, 0.8]).expand(int(mask.sum()), 3))
    assert (img[~mask] == 0).all()


def test_light_from_up_lights_the_top():
    img = render_sphere(directional_light([0.0, 0.0, 1.0], 1.0, 2), S)[..., 0]  # +z_light = up
    top, bottom = img[S // 8, S // 2], img[S - 1 - S // 8, S // 2]
    assert top > bottom + 0.1
    assert img[: S // 2].sum() > img[S // 2 :].sum()


def test_light_toward_camera_lights_the_centre():
    img = render_sphere(directional_light([1.0, 0.0, 0.0], 1.0, 2), S)[..., 0]  # +x_light = toward camera
    i, j = divmod(int(img.argmax()), S)
    assert abs(i - (S - 1) / 2) <= 1 and abs(j - (S - 1) / 2) <= 1
    back = render_sphere(directional_light([1.0, 0.0, 0.0], 1.0, 2), S, "back")[..., 0]
    # Closed form at order 2 (Â = π, 2π/3, π/4): E(n·d = t) = 1/4 + t/2 + 5/32 (3t² − 1).
    # Pixel (S/2, S/2) sits at x = y = 1/S, so its normal has n·d = √(1 − 2/S²).
    t_front = torch.tensor(1 - 2 / S**2).sqrt()

    def e(t):
        return 0.25 + t / 2 + 5 / 32 * (3 * t * t - 1)

    torch.testing.assert_close(img[S // 2, S // 2], e(t_front) / torch.pi, rtol=1e-4, atol=0)
    torch.testing.assert_close(back[S // 2, S // 2], e(-t_front) / torch.pi, rtol=1e-3, atol=0)
    assert back[S // 2, S // 2] < 0.1 * img.max()  # facing away: (almost) unlit


def test_light_from_image_right_lights_the_right_side():
    img = render_sphere(directional_light([0.0, 1.0, 0.0], 1.0, 2), S)[..., 0]  # +y_light = image right
    assert img[S // 2, S - 1 - S // 8] > img[S // 2, S // 8] + 0.1


def test_preview_layout_and_auto_exposure():
    sh = directional_light([1.0, 1.0, 1.0], [1.0, 0.8, 0.6], 2) + ambient_light(0.1)
    img = light_preview(sh, S)
    assert img.dtype == torch.uint8 and img.shape == (S, S + 4 + S + 4 + 2 * S, 3)
    # A 1000x dimmer or brighter light gives the same picture with auto exposure.
    for k in (1e-3, 1e3):
        assert (light_preview(sh * k, S).int() - img.int()).abs().max() <= 1
    assert img[:, :S].max() >= 235  # the sphere's bright part is near white, not clipped everywhere
    env = torch.rand(32, 64, 3)
    assert light_preview(sh, S, env=env).shape == (S, 2 * S + 2 * S + 2 * S + 12, 3)
    dim = light_preview(sh, S, exposure=1e-3)
    assert dim.float().mean() < img.float().mean()


def test_preview_of_sequence_and_black_light():
    seq = torch.stack([directional_light([1.0, 0.0, 0.0], 1.0, 2) * (t + 1) for t in range(12)])
    img = light_preview(seq, 32, max_frames=5)
    assert img.shape == (32, 5 * 32 + 4 * 4, 3)
    black = light_preview(torch.zeros(9, 3), 16)
    assert black.max() == 0


def test_preview_and_sphere_errors():
    with pytest.raises(ShapeError):
        render_sphere(torch.zeros(8, 3), S)
    with pytest.raises(InputError, match="NaN"):
        render_sphere(torch.full((9, 3), float("nan")), S)
    with pytest.raises(InputError, match="exposure"):
        light_preview(ambient_light(1.0), 16, exposure="bright")
    with pytest.raises(InputError, match="exposure"):
        light_preview(ambient_light(1.0), 16, exposure=-1.0)
    with pytest.raises(InputError, match="view"):
        sphere_normals(8, "side")


def test_render_presets_writes_every_preset(tmp_path):
    paths = render_presets(tmp_path / "demo", size=32)
    assert [p.stem for p in paths] == preset_names()
    for p in paths:
        img = read_image(p)
        assert img.shape == (32, 32 * 6 + 12, 3)
        assert img[:, :32].max() > 0.5  # a visible, lit sphere
