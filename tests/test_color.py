import numpy as np
import torch

from relightnet import color
from relightnet.color import linear_to_srgb, srgb_to_linear


def test_the_srgb_functions_live_in_color_only():
    import relightnet.io

    assert linear_to_srgb is color.linear_to_srgb and srgb_to_linear is color.srgb_to_linear
    assert not hasattr(relightnet.io, "linear_to_srgb") and "srgb_to_linear" not in relightnet.io.__all__


def test_transfer_functions_known_values_and_inverse():
    x = torch.tensor([0.0, 0.0031308, 0.5, 1.0], dtype=torch.float64)
    y = color.linear_to_srgb(x)
    torch.testing.assert_close(y[[0, 3]], torch.tensor([0.0, 1.0], dtype=torch.float64))
    torch.testing.assert_close(y[1], torch.tensor(12.92 * 0.0031308, dtype=torch.float64))
    torch.testing.assert_close(color.srgb_to_linear(y), x, rtol=0, atol=1e-12)


def test_numpy_form_equals_the_tensor_form():
    c = np.linspace(-0.05, 1.1, 101)
    want = color.srgb_to_linear(torch.from_numpy(c)).numpy()
    np.testing.assert_allclose(color.srgb_to_linear_np(c), want, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(color.srgb_to_linear_np(c, clip=True), color.srgb_to_linear_np(np.clip(c, 0, 1)))
    assert color.srgb_to_linear_np([0.5]).dtype == np.float64


def test_luminance_weights_sum_to_one_and_follow_the_device_and_dtype():
    assert abs(sum(color.LUMA) - 1) < 1e-12
    rgb = torch.tensor([[1.0, 1.0, 1.0], [0.0, 1.0, 0.0]], dtype=torch.float64)
    lum = color.luminance(rgb)
    assert lum.dtype == torch.float64
    torch.testing.assert_close(lum, torch.tensor([1.0, 0.7152], dtype=torch.float64))
    assert color.luminance(np.ones((2, 3), np.float32)).shape == (2,)
