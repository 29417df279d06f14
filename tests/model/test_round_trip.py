import pytest
import torch

from relightnet.checks import InputError
from relightnet.color import linear_to_srgb, luminance, srgb_to_linear
from relightnet.light import directional_light
from relightnet.model import Prediction, normalize_input, shading_map
from relightnet.model.round_trip import novel_lights, relit_input, round_trip_loss
from relightnet.sh import scale_invariant_light_error


def _scene(b=3, k=9, s=16, seed=0):
    g = torch.Generator().manual_seed(seed)
    mask = torch.zeros(b, 1, s, s)
    mask[:, :, 3:13, 5:11] = 1
    albedo = 0.2 + 0.6 * torch.rand(b, 3, s, s, generator=g)
    transport = 0.3 * torch.randn(b, k, s, s, generator=g)
    transport[:, 0] = 1.0  # a positive l = 0 term: the shading stays positive
    light = 0.1 * torch.randn(b, k, 3, generator=g)
    light[:, 0] = 1.0
    image = (albedo * shading_map(transport, light)).clamp(0, 1)
    x = normalize_input(linear_to_srgb(image), mask)
    return x, Prediction(albedo, transport, light, mask), light, mask


def test_batch_lights_are_the_batch_rolled_and_side_lights_come_from_the_camera_side():
    light = torch.randn(6, 9, 3)
    torch.testing.assert_close(novel_lights(light, "batch"), light.roll(1, 0))
    draw = novel_lights(light, "side", torch.Generator().manual_seed(3))
    torch.testing.assert_close(draw, novel_lights(light, "side", torch.Generator().manual_seed(3)))  # seeded
    side = [i for i in range(6) if not torch.equal(draw[i], light.roll(1, 0)[i])]
    assert side  # 6 coin tosses: seed 3 gives at least one side light
    toward_camera = directional_light((1.0, 0.0, 0.0), 1.0, 2)[1:4, 0]
    for i in side:
        d = draw[i]
        torch.testing.assert_close(d[:, 0], d[:, 1])  # white
        torch.testing.assert_close(d[:, 0], d[:, 2])
        assert float(d[1:4, 0] @ toward_camera) >= 0  # its l = 1 band points to the camera's half
        assert 0.2821 * 1.0 + 0.1 <= float(d[0, 0]) <= 0.2821 * 4.0 + 0.5 + 1e-5  # power·Y00 + ambient
    with pytest.raises(InputError, match="novel_light"):
        novel_lights(light, "sun")


def test_relit_to_its_own_light_the_input_comes_back():
    x, pred, light, _ = _scene()
    x2, scaled = relit_input(x, pred, 2.5 * light)  # the exposure is kept: the scale goes
    torch.testing.assert_close(scaled, light, atol=1e-5, rtol=1e-5)
    torch.testing.assert_close(x2, x, atol=2e-5, rtol=0)


def test_relit_input_shades_the_photo_albedo_with_the_predicted_transport():
    x, pred, light, mask = _scene()
    new = light.roll(1, 0)
    x2, scaled = relit_input(x, pred, new)
    torch.testing.assert_close(x2[:, 3:], mask)
    assert float(x2[:, :3].abs().mul(1 - mask).max()) == 0  # nothing outside the mask
    expected = linear_to_srgb((pred.albedo * shading_map(pred.transport, scaled)).clamp(0, 1))
    srgb = (x2[:, :3] + 1) / 2
    torch.testing.assert_close(srgb * mask, expected * mask, atol=1e-4, rtol=0)
    # the exposure is the photo's: the same mean shading luminance over the mask, per item
    def level(lt):
        return (luminance(shading_map(pred.transport, lt).movedim(1, -1))[:, None] * mask).sum((1, 2, 3))

    torch.testing.assert_close(level(scaled), level(light), rtol=1e-5, atol=0)
    assert not torch.allclose(srgb_to_linear(srgb) * mask, srgb_to_linear((x[:, :3] + 1) / 2) * mask, atol=1e-2)


def test_round_trip_loss_scores_the_light_read_back_and_trains_the_second_pass_only():
    x, pred, light, _ = _scene()
    pred.transport.requires_grad_(True)  # the first prediction: no gradient reaches it
    new = light.roll(1, 0)
    _, scaled = relit_input(x, pred, new)
    right = round_trip_loss(lambda x2: Prediction(pred.albedo, pred.transport, 3.0 * scaled, pred.mask), x, pred, new)
    # the light read back is the light relit with, at any scale (a square root of float32 rounding: ~1e-4)
    assert float(right.detach()) < 1e-3
    wrong = torch.nn.Parameter(light.clone())
    loss = round_trip_loss(lambda x2: Prediction(pred.albedo, pred.transport, wrong, pred.mask), x, pred, new)
    torch.testing.assert_close(loss, scale_invariant_light_error(light, scaled).mean())
    loss.backward()
    assert wrong.grad is not None and float(wrong.grad.abs().sum()) > 0
    assert pred.transport.grad is None
