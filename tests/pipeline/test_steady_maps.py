"""The CNN's maps carried along the flow: steadier on a still scene, following a moving one, reset cleanly."""

import pytest
import torch

from relightnet.checks import InputError
from relightnet.model.inference import CropBox, CropMaps
from relightnet.pipeline.steady_maps import MapCarry, carry_positions


def _scene(h=80, w=80, shift=0, seed=0):
    g = torch.Generator().manual_seed(seed)
    tex = torch.nn.functional.interpolate(torch.rand(1, 3, 10, 10, generator=g), size=(h, w + 20), mode="bicubic",
                                          align_corners=False)[0].clamp(0, 1)
    return tex[:, :, 10 - shift:10 - shift + w]


def _maps(transport, mask, box):
    return CropMaps(albedo=torch.full((1, 3) + transport.shape[-2:], 0.5), transport=transport,
                    light=torch.zeros(1, 9, 3), mask=mask, box=box)


def test_carry_positions_map_crops_through_the_frame():
    box = CropBox(10, 20, 64)
    flow = torch.zeros(32, 32, 2).numpy()
    pos = carry_positions(flow, box, box, 32, 32)
    u = torch.arange(32.0)
    torch.testing.assert_close(pos[..., 0], u[None].expand(32, 32))
    moved = carry_positions(flow, box, CropBox(10, 36, 64), 32, 32)  # the previous crop 16 px (8 crop px) right
    torch.testing.assert_close(moved[..., 0], u[None].expand(32, 32) - 8)
    torch.testing.assert_close(moved[..., 1], pos[..., 1])


def test_a_still_scene_gets_steadier_maps():
    img, mask, box = _scene(), torch.ones(1, 1, 80, 80), CropBox(0, 0, 80)
    g = torch.Generator().manual_seed(1)
    truth = torch.rand(1, 9, 40, 40, generator=g)
    carry = MapCarry()
    own, carried = [], []
    for _ in range(12):
        t = truth + 0.1 * torch.randn(truth.shape, generator=g)  # each frame's prediction scatters
        own.append(t)
        carried.append(carry(img, _maps(t, mask, box)).transport)
    err = lambda xs: float(torch.stack([(x - truth).abs().mean() for x in xs[6:]]).mean())  # noqa: E731
    assert err(carried) < 0.5 * err(own)
    torch.testing.assert_close(carried[0], own[0])  # the first frame is its own prediction


def test_a_moving_scene_moves_the_carried_maps_and_a_reset_forgets():
    mask, box = torch.ones(1, 1, 80, 80), CropBox(0, 0, 80)
    stripes = (torch.arange(100.0) % 20 < 10).float()  # a pattern fixed on the moving surface
    carry = MapCarry(carry=0.9)
    for k in range(4):
        img = _scene(shift=2 * k)
        on_surface = stripes[10 - 2 * k:90 - 2 * k].expand(1, 9, 80, 80)
        out = carry(img, _maps(on_surface, mask, box)).transport
    # every frame predicted the pattern where the surface put it; the carried maps agree with the last one
    assert float((out - on_surface)[..., 10:-10].abs().mean()) < 0.1
    carry.reset()
    other = torch.rand(1, 9, 80, 80)
    torch.testing.assert_close(carry(_scene(shift=6), _maps(other, mask, box)).transport, other)


def test_bad_weight():
    with pytest.raises(InputError, match="carry"):
        MapCarry(carry=1.0)
