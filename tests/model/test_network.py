import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.model import (
    NetConfig,
    Prediction,
    RelightNet,
    normalize_input,
    pad_to_multiple,
    relight,
    shading_map,
)

TINY = NetConfig(width=8, max_width=32, light_hidden=32)


@pytest.mark.parametrize("b,h,w", [(1, 32, 32), (2, 48, 64), (3, 64, 16)])
def test_output_shapes_and_ranges(b, h, w):
    net = RelightNet(TINY)
    p = net(normalize_input(torch.rand(b, 3, h, w), torch.ones(b, 1, h, w)))
    assert p.albedo.shape == (b, 3, h, w) and p.transport.shape == (b, 9, h, w)
    assert p.light.shape == (b, 9, 3) and p.mask.shape == (b, 1, h, w)
    assert p.albedo.dtype == torch.float32
    assert 0 <= p.albedo.min() and p.albedo.max() <= 1 and 0 <= p.mask.min() and p.mask.max() <= 1
    assert relight(p, torch.randn(9, 3)).shape == (b, 3, h, w)


def test_batch_independence_groupnorm():
    net = RelightNet(TINY).eval()
    x = normalize_input(torch.rand(3, 3, 32, 32), torch.ones(3, 1, 32, 32))
    with torch.no_grad():
        full = net(x)
        one = net(x[1:2])
    torch.testing.assert_close(full.light[1:2], one.light, atol=1e-5, rtol=1e-4)
    torch.testing.assert_close(full.transport[1:2], one.transport, atol=1e-5, rtol=1e-4)


def test_gradients_reach_every_parameter():
    net = RelightNet(TINY)
    p = net(normalize_input(torch.rand(2, 3, 32, 32), torch.ones(2, 1, 32, 32)))
    (p.albedo.mean() + p.transport.mean() + p.light.mean() + p.mask.mean()).backward()
    missing = [n for n, q in net.named_parameters() if q.grad is None or not torch.isfinite(q.grad).all()]
    assert not missing


def test_relight_is_albedo_times_shading():
    A, T, L = torch.rand(2, 3, 4, 5), torch.randn(2, 9, 4, 5), torch.randn(9, 3)
    p = Prediction(A, T, torch.randn(2, 9, 3))
    expected = A * torch.einsum("bkhw,kc->bchw", T, L)
    torch.testing.assert_close(relight(p, L), expected)
    torch.testing.assert_close(p.shading(L), shading_map(T, L))


def test_input_normalisation_like_ke18():
    img = torch.full((1, 3, 2, 2), 1.0)
    mask = torch.tensor([[[[1.0, 0.0], [1.0, 1.0]]]])
    x = normalize_input(img, mask)
    assert x.shape == (1, 4, 2, 2)
    assert x[0, :3, 0, 0].tolist() == [1.0, 1.0, 1.0] and x[0, :3, 0, 1].tolist() == [0.0, 0.0, 0.0]
    assert normalize_input((img * 255).to(torch.uint8), mask).allclose(x)


def test_sizes_not_multiple_of_16_are_rejected_or_padded():
    net = RelightNet(TINY)
    x = normalize_input(torch.rand(1, 3, 30, 33), torch.ones(1, 1, 30, 33))
    with pytest.raises(InputError, match="multiples of 16"):
        net(x)
    xp, orig = pad_to_multiple(x, 16)
    assert xp.shape[-2:] == (32, 48) and orig == (30, 33)
    assert net(xp).albedo.shape[-2:] == (32, 48)
    with pytest.raises(ShapeError):
        net(torch.rand(1, 3, 32, 32))


def test_cone_head_predicts_the_transport_of_a_cone():
    from relightnet.model.network import cone_maps
    from relightnet.sh import cone_transport
    from relightnet.sh.irradiance import cone_band_factors

    net = RelightNet(NetConfig(width=8, max_width=32, light_hidden=32, transport_head="cone", light_mode="hybrid"))
    x = normalize_input(torch.rand(2, 3, 32, 32), torch.ones(2, 1, 32, 32))
    p = net(x)
    assert p.transport.shape == (2, 9, 32, 32) and p.confidence.shape == (2, 1, 32, 32)
    # Every pixel is the transport of some cone: the l = 0 term within [0, g_0(0) Y_00] and the l = 1 vector
    # no longer than g_1 of that cone, whatever the weights.
    g = cone_band_factors(torch.tensor([0.0]), 2)[0]
    y00 = 0.28209479177387814
    t0 = p.transport[:, 0] / y00
    assert t0.min() >= 0 and t0.max() <= g[0] + 1e-5
    raw = torch.randn(1, 4, 3, 5)
    axis = torch.nn.functional.normalize(raw[:, :3], dim=1).permute(0, 2, 3, 1)
    want = cone_transport(axis, torch.sigmoid(raw[:, 3]), 2).permute(0, 3, 1, 2)
    torch.testing.assert_close(cone_maps(raw, 2), want)
    (p.transport.mean() + p.light.mean() + p.albedo.mean()).backward()
    assert all(q.grad is not None for q in net.parameters())


def test_unknown_transport_head_is_refused():
    with pytest.raises(InputError, match="transport_head"):
        NetConfig(transport_head="spline")



LOWRES = NetConfig(width=8, max_width=32, light_hidden=32, light_mode="hybrid", transport_head="cone", work_scale=2)


@pytest.mark.parametrize("b,h,w", [(2, 112, 112), (1, 32, 48), (1, 16, 16)])
def test_half_resolution_network_gives_full_size_maps(b, h, w):
    """work_scale 2: the CNN at H/2 (112 → 56: its deepest level rounds 7 up to 4), maps at H × W."""
    net = RelightNet(LOWRES)
    image, mask = torch.rand(b, 3, h, w), (torch.rand(b, 1, h, w) > 0.3).float()
    p = net(normalize_input(image, mask))
    assert p.albedo.shape == (b, 3, h, w) and p.transport.shape == (b, 9, h, w)
    assert p.mask.shape == (b, 1, h, w) and p.confidence.shape == (b, 1, h, w) and p.light.shape == (b, 9, 3)
    assert 0 <= p.albedo.min() and p.albedo.max() <= 1 and 0 <= p.mask.min() and p.mask.max() <= 1
    assert torch.isfinite(p.light).all() and torch.isfinite(p.transport).all()
    (p.albedo.mean() + p.transport.mean() + p.light.mean() + p.mask.mean()).backward()
    missing = [n for n, q in net.named_parameters() if q.grad is None or not torch.isfinite(q.grad).all()]
    assert not missing


def test_half_resolution_pose_network_reads_the_full_size_input():
    cfg = NetConfig(width=8, max_width=32, light_hidden=32, encoder="pose", work_scale=2)
    net = RelightNet(cfg).eval()
    assert net.pose.upsample == 1 and RelightNet(NetConfig(width=8, max_width=32, encoder="pose")).pose.upsample == 2
    with torch.no_grad():
        p = net(normalize_input(torch.rand(1, 3, 48, 80), torch.ones(1, 1, 48, 80)))
    assert p.albedo.shape == (1, 3, 48, 80)


def test_work_scale_defaults_to_full_resolution_and_is_checked():
    assert NetConfig().work_scale == 1
    net = RelightNet(TINY)
    assert net.up_t is None and not any(k.startswith(("up_t", "up_a")) for k in net.state_dict())
    for bad in (0, 3, True):
        with pytest.raises(InputError, match="work_scale"):
            NetConfig(work_scale=bad)


def test_a_checkpoint_without_work_scale_loads_at_full_resolution(tmp_path):
    from relightnet.model import load_model, save_checkpoint

    torch.manual_seed(0)
    net = RelightNet(TINY).eval()
    save_checkpoint(tmp_path / "c.pt", net, TINY, step=1)
    state = torch.load(tmp_path / "c.pt", weights_only=True)
    del state["net_config"]["work_scale"]  # as written before the option existed
    torch.save(state, tmp_path / "old.pt")
    old = load_model(tmp_path / "old.pt").eval()
    assert old.config.work_scale == 1
    x = normalize_input(torch.rand(1, 3, 32, 32), torch.ones(1, 1, 32, 32))
    with torch.no_grad():
        assert torch.equal(old(x).transport, net(x).transport)
