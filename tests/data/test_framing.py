import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.data.framing import (
    CROP_MODES,
    base_camera,
    camera_intrinsics,
    crop_camera,
    draw_view,
    place_in_camera,
)
from relightnet.raster import default_camera, perspective_camera, rasterize


def _base():
    return perspective_camera(torch.eye(4)[None], (1024, 1024), intrinsics=(1000.0, 1000.0, 512.0, 512.0))


def _person(seed=0):
    """A cloud of points shaped like a standing person, 3–5 m in front of the camera."""
    g = torch.Generator().manual_seed(seed)
    p = torch.rand(4000, 3, generator=g) * torch.tensor([0.5, 1.75, 0.3]) - torch.tensor([0.25, 1.2, 4.0])
    return p


@pytest.mark.parametrize("seed", range(8))
def test_full_crop_contains_everything_with_the_padding(seed):
    rng = np.random.default_rng(seed)
    v = _person(seed)
    pad, jitter, res = 0.05, 0.1, 64
    cam, box = crop_camera(v, _base(), res, pad, jitter, rng, "full")
    assert cam.size == (res, res) and torch.equal(cam.view, torch.eye(4)[None])  # rotation kept
    uv = cam.project(v)[0]
    base_uv = _base().project(v)[0]
    big = float((base_uv.amax(0) - base_uv.amin(0)).max())
    margin = pad * big * res / box.side  # the guaranteed margin, in output pixels
    assert margin > 1.0
    assert float(uv.min()) >= margin - 1e-3 and float(uv.max()) <= res - margin + 1e-3
    # The crop is the box: output pixels = (base pixels − corner) · res / side.
    expect = (base_uv - torch.tensor([box.u0, box.v0])) * (res / box.side)
    assert torch.allclose(uv, expect, atol=1e-3)


def test_crop_without_jitter_is_centred_and_tight():
    v = _person(1)
    cam, box = crop_camera(v, _base(), 32, pad=0.1, jitter=0.0, rng=None)
    uv = cam.project(v)[0]
    lo, hi = uv.amin(0), uv.amax(0)
    assert float((lo + hi)[0] / 2) == pytest.approx(16, abs=1e-3)
    assert float((lo + hi)[1] / 2) == pytest.approx(16, abs=1e-3)
    assert float((hi - lo).max()) == pytest.approx(32 / 1.2, abs=1e-3)  # larger side fills 1/(1+2·pad)


def test_mask_of_a_mesh_stays_inside_the_full_crop():
    # A real rasterized silhouette: a box mesh, cropped, never touches the border band.
    import trimesh

    m = trimesh.creation.box(extents=(0.5, 1.7, 0.3))
    v = torch.tensor(m.vertices, dtype=torch.float32) + torch.tensor([0.2, 0.1, -3.5])
    f = torch.tensor(m.faces, dtype=torch.int64)
    for seed in range(4):
        cam, _ = crop_camera(v, _base(), 48, 0.1, 0.2, np.random.default_rng(seed))
        mask = rasterize(cam.transform(v), f, cam.size).mask[0]
        rows, cols = torch.nonzero(mask, as_tuple=True)
        assert rows.min() >= 1 and cols.min() >= 1 and rows.max() <= 46 and cols.max() <= 46


@pytest.mark.parametrize("mode", ["upper", "head"])
def test_partial_crops_frame_the_top_of_the_body(mode):
    v = _person(2)
    full, fbox = crop_camera(v, _base(), 64, 0.05, 0.0, None, "full")
    cam, box = crop_camera(v, _base(), 64, 0.05, 0.0, None, mode)
    assert box.side < fbox.side and box.mode == mode
    uv = cam.project(v)[0]
    top = v[:, 1].argmax()  # the highest point is in the crop, the lowest is cut off
    assert 0 <= float(uv[top, 1]) <= 64
    assert float(uv[v[:, 1].argmin(), 1]) > 64


def test_intrinsics_round_trip_and_other_base_cameras():
    cam = perspective_camera(torch.eye(4)[None], (100, 120), intrinsics=(90.0, 95.0, 61.0, 48.0))
    assert camera_intrinsics(cam) == pytest.approx((90.0, 95.0, 61.0, 48.0), abs=1e-4)
    # A rotated base camera (the default camera looks at the origin from +z): the view is kept.
    base = default_camera(256)
    v = _person(3) + torch.tensor([0.0, 1.5, 4.0])
    cam, _ = crop_camera(v, base, 32, 0.05, 0.0, None)
    assert torch.equal(cam.view, base.view)
    uv = cam.project(v)[0]
    assert float(uv.min()) > 0 and float(uv.max()) < 32


def test_placement_in_the_camera_frame():
    views = [draw_view(np.random.default_rng(s), 0.5) for s in range(40)]
    assert {v["mode"] for v in views} == set(CROP_MODES) and all(2.5 <= v["distance"] <= 6 for v in views
                                                                  if v["mode"] == "full")
    assert {draw_view(np.random.default_rng(s), 0.0)["mode"] for s in range(10)} == {"full"}
    v = _person(1)[None] + torch.tensor([0.0, 1.2, 4.0])  # standing on y = 0 near the origin
    n = torch.nn.functional.normalize(torch.randn(v.shape, generator=torch.Generator().manual_seed(0)), dim=-1)
    joints = torch.zeros(1, 2, 3)
    v_cam, n_cam, R, pitch, w2c = place_in_camera(v, n, joints, views[0], 0.4)
    # world_to_camera (before the yaw) is what moved the vertices and turned the normals; R is the pitch.
    torch.testing.assert_close(v_cam[0].double(), v[0].double() @ w2c[:3, :3].T + w2c[:3, 3], atol=1e-5, rtol=0)
    torch.testing.assert_close(n_cam[0].double(), n[0].double() @ w2c[:3, :3].T, atol=1e-6, rtol=0)
    torch.testing.assert_close(R, torch.tensor([[1.0, 0, 0], [0, np.cos(pitch), -np.sin(pitch)],
                                                [0, np.sin(pitch), np.cos(pitch)]], dtype=torch.float64))
    assert float(v_cam[0, :, 2].max()) < 0  # in front of the camera (it looks along -z)
    assert camera_intrinsics(base_camera()) == pytest.approx((1000.0, 1000.0, 512.0, 512.0), abs=1e-3)


def test_bad_inputs_raise():
    v = _person()
    with pytest.raises(InputError):
        crop_camera(v, _base(), 64, mode="feet")
    with pytest.raises(InputError):
        crop_camera(v, _base(), 0)
    with pytest.raises(InputError):
        crop_camera(v, _base(), 64, pad=1.5)
    with pytest.raises(InputError):
        crop_camera(v * torch.tensor([1.0, 1.0, -1.0]), _base(), 64)  # behind the camera
    assert CROP_MODES == ("full", "upper", "head")
