import pytest
import torch

from relightnet.checks import InputError
from relightnet.model import NetConfig, RelightNet, estimate_light, predict_image
from relightnet.model.inference import _check_predicted_mask, check_predicted_person, mask_crop_box


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


@pytest.mark.parametrize("box, h, w", [((-50, 30, 700), 600, 70), ((3, -4, 37), 40, 30), ((-10, -10, 13), 9, 20),
                                       ((5, 7, 100), 120, 150), ((200, 0, 10), 50, 50)])
def test_paste_rows_are_the_rows_of_the_whole_paste(box, h, w):
    """paste_rows gives any band of rows of paste_from_box (to float32 rounding of the source position),
    for a box inside, across or outside the photo's edges."""
    from relightnet.model.inference import CropBox, paste_from_box, paste_rows

    torch.manual_seed(0)
    x = torch.randn(1, 9, 32, 32)
    full = paste_from_box(x, CropBox(*box), h, w)
    for step in (256, 7):
        bands = torch.cat([paste_rows(x, CropBox(*box), h, w, r, min(r + step, h)) for r in range(0, h, step)], -2)
        torch.testing.assert_close(bands, full, rtol=0, atol=2e-5)


def test_crop_maps_paste_as_predict_image(net):
    from relightnet.model.inference import predict_crop

    img, m = torch.rand(3, 90, 70), torch.zeros(90, 70)
    m[10:80, 20:50] = 1
    crop = predict_crop(net, img, m, size=32)
    assert crop.albedo.shape == (1, 3, 32, 32) and crop.size == (90, 70)
    pred, box = predict_image(net, img, m, size=32)
    assert box == crop.box
    torch.testing.assert_close(crop.pasted().transport, pred.transport)
    a, t, mk = crop.rows(20, 50)
    torch.testing.assert_close(t, pred.transport[:, :, 20:50], rtol=0, atol=1e-5)
    torch.testing.assert_close(a, pred.albedo[:, :, 20:50], rtol=0, atol=1e-5)
    assert crop.rows(0, 5, albedo=False)[0] is None and torch.equal(mk, pred.mask[:, :, 20:50])
