import pytest
import torch

from relightnet.checks import InputError
from relightnet.model import NetConfig, RelightNet, estimate_light, mask_crop_box, predict_image
from relightnet.model.inference import _check_predicted_mask, check_predicted_person


@pytest.fixture(scope="module")
def net():
    torch.manual_seed(0)
    return RelightNet(NetConfig(width=8, max_width=32, light_hidden=32)).eval()


def test_crop_box_is_square_padded_and_centred():
    m = torch.zeros(100, 80)
    m[20:60, 30:50] = 1  # 40 tall, 20 wide
    b = mask_crop_box(m, pad=0.05)
    assert b.size == 44 and b.top == 18 and b.left == 18
    with pytest.raises(InputError, match="mask: empty"):
        mask_crop_box(torch.zeros(4, 4))


def test_predict_pastes_back_at_original_resolution(net):
    img = torch.rand(3, 90, 70)
    m = torch.zeros(90, 70)
    m[10:80, 20:50] = 1
    pred, box = predict_image(net, img, m, size=32)
    assert pred.albedo.shape == (1, 3, 90, 70) and pred.transport.shape == (1, 9, 90, 70)
    assert pred.light.shape == (1, 9, 3)
    # Outside the mask the maps are zero, inside they are the network's.
    assert pred.albedo[0, :, m == 0].abs().max() == 0 and pred.albedo[0, :, m == 1].abs().min() > 0
    torch.testing.assert_close(estimate_light(net, img, m, size=32), pred.light[0])


def test_without_mask_uses_the_mask_head_or_fails_clearly(net, caplog):
    img = torch.rand(3, 40, 64)
    head = net.albedo_dec.head
    with torch.no_grad():
        saved = head.bias[3].item()
        head.bias[3] = 50.0  # the mask head says "person" everywhere: a mask of everything is no person
        with pytest.raises(InputError, match="100.0% of the frame.*mask of everything"):
            predict_image(net, img, None, size=32)
        head.bias[3] = -50.0  # ... or nowhere: a clear error
        with pytest.raises(InputError, match="found no person"):
            predict_image(net, img, None, size=32)
        head.bias[3] = saved
    # A black or one-colour frame is refused before the network looks for a person in it.
    for blank in (torch.zeros(3, 40, 64), torch.full((3, 40, 64), 0.5)):
        with pytest.raises(InputError, match="image: blank"):
            predict_image(net, blank, None, size=32)
    # Most of the frame and its top edge (not all of it): accepted with a warning.
    person = torch.zeros(40, 64, dtype=torch.bool)
    person[:, :50] = True
    check_predicted_person(person)
    _check_predicted_mask(person)
    assert "may have taken the background for the person" in caplog.text
    with pytest.raises(InputError, match="multiple of 16"):
        predict_image(net, img, torch.ones(40, 64), size=40)
