import pytest
import torch

from relightnet.checks import InputError
from relightnet.model import NetConfig, RelightNet
from relightnet.pipeline.backends import BACKENDS, TorchPredictor, as_predictor, make_predictor


def _photo():
    img = torch.rand(3, 48, 40)
    mask = torch.zeros(48, 40)
    mask[6:44, 10:30] = 1
    return img, mask


@pytest.mark.slow
def test_torch_predictor_light_is_the_prediction_light():
    net = RelightNet(NetConfig(width=8, levels=2, mask_head=True)).eval()
    p = as_predictor(net)
    assert isinstance(p, TorchPredictor) and p.lmax == 2 and p.has_mask_head
    assert as_predictor(p) is p
    img, mask = _photo()
    pred = p(img, mask)
    assert pred.albedo.shape == (1, 3, 48, 40) and pred.transport.shape == (1, 9, 48, 40)
    torch.testing.assert_close(p.light(img, mask), pred.light[0], rtol=1e-5, atol=1e-6)
    assert (pred.albedo[0, :, mask == 0] == 0).all()  # maps only inside the person
    assert p(img, None).mask.shape == (1, 1, 48, 40)  # the mask head finds a mask


def test_make_predictor_and_bad_choices(tmp_path):
    assert BACKENDS == ("torch", "onnx")
    assert isinstance(make_predictor("torch"), TorchPredictor)
    with pytest.raises(InputError, match="backend"):
        make_predictor("tensorrt")
    with pytest.raises(InputError, match="needs --backend onnx"):
        make_predictor("torch", tmp_path / "m.onnx")
    with pytest.raises(InputError, match="CPU"):
        make_predictor("onnx", device="cuda")
    with pytest.raises(InputError, match="checkpoint not found"):
        make_predictor("onnx", tmp_path / "missing.pt")
    with pytest.raises(InputError, match="RelightNet or a predictor"):
        as_predictor("model.pt")


@pytest.mark.slow
def test_onnx_predictor_needs_masks_and_matches_torch(tmp_path):
    from relightnet.model.onnx_export import export_onnx
    from relightnet.pipeline.backends import OnnxPredictor

    net = RelightNet(NetConfig(width=8, levels=2, input_size=32)).eval()  # the working size is the config's
    export_onnx(net, tmp_path / "t.onnx", smoothing="none", example_size=32)
    onnx = OnnxPredictor(tmp_path / "t.onnx")
    assert onnx.size == 32 and onnx.lmax == 2 and not onnx.has_mask_head
    img, mask = _photo()
    with pytest.raises(InputError, match="no mask head"):
        onnx(img, None)
    want = TorchPredictor(net, size=32)(img, mask)
    got = onnx(img, mask)
    torch.testing.assert_close(got.light, want.light, rtol=1e-4, atol=1e-4)
    torch.testing.assert_close(got.transport, want.transport, rtol=1e-4, atol=1e-4)
    torch.testing.assert_close(onnx.light(img, mask), want.light[0], rtol=1e-4, atol=1e-4)


@pytest.mark.slow
def test_predictors_follow_the_protocol_and_take_their_size_from_the_config(tmp_path):
    from relightnet.model import save_checkpoint
    from relightnet.pipeline.backends import Predictor

    net = RelightNet(NetConfig(width=8, levels=2, input_size=48)).eval()
    p = as_predictor(net)
    assert isinstance(p, Predictor) and p.size == 48
    assert as_predictor(net, size=32).size == 32
    with pytest.raises(InputError, match="works at 48"):
        as_predictor(p, size=64)
    ckpt = save_checkpoint(tmp_path / "m.pt", net, net.config, step=0)
    assert make_predictor("torch", ckpt).size == 48 and make_predictor("torch", ckpt, size=32).size == 32
    with pytest.raises(InputError, match="multiple of 16"):
        make_predictor("torch", ckpt, size=40)
    from relightnet.model.onnx_export import export_onnx

    export_onnx(net, tmp_path / "m.onnx", smoothing="none", example_size=32)
    onnx = make_predictor("onnx", tmp_path / "m.onnx")
    assert isinstance(onnx, Predictor) and onnx.size == 48


def test_crop_and_paste_are_public_and_inverse():
    from relightnet.model.inference import CropBox, crop_to_box, paste_from_box

    x = torch.rand(1, 2, 20, 30)
    box = CropBox(-3, 5, 16)
    c = crop_to_box(x, box)
    assert c.shape == (1, 2, 16, 16) and (c[..., :3, :] == 0).all()
    back = paste_from_box(c, box, 20, 30)
    torch.testing.assert_close(back[..., 0:13, 5:21], x[..., 0:13, 5:21])
    assert (back[..., :, :5] == 0).all()


def _layouts(model):
    return [(n, t.data_ptr(), t.stride()) for n, t in [*model.named_parameters(), *model.named_buffers()]]


def test_the_callers_model_is_left_as_it_was_and_the_prediction_is_the_channels_last_one():
    """The predictor runs a channels-last copy: the caller's weights keep their memory format, storage and
    values, and the prediction is bit for bit that of the model switched to channels-last."""
    import copy

    net = RelightNet(NetConfig(width=8, levels=2, input_size=32)).eval()
    before, state = _layouts(net), {k: v.clone() for k, v in net.state_dict().items()}
    img, mask = _photo()
    got = as_predictor(net)(img, mask)
    assert _layouts(net) == before and all(torch.equal(v, state[k]) for k, v in net.state_dict().items())
    assert all(p.is_contiguous() for p in net.parameters()) and any(p.dim() == 4 for p in net.parameters())
    want = TorchPredictor(copy.deepcopy(net).to(memory_format=torch.channels_last))(img, mask)
    assert torch.equal(got.albedo, want.albedo) and torch.equal(got.transport, want.transport)
    assert torch.equal(got.light, want.light)
    switched = copy.deepcopy(net).to(memory_format=torch.channels_last)
    assert TorchPredictor(switched).model is switched  # channels-last already: used as it is, no copy
