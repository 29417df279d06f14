"""Model-test fixtures: one small network exported to ONNX (EMA smoothing) per session, input frames."""

import pytest
import torch

from relightnet.model import NetConfig, RelightNet

NET = NetConfig(width=8, max_width=32, light_hidden=32)
#: The smallest network of the checkpoint tests.
TINY = NetConfig(width=4, max_width=8, levels=2, light_hidden=8)


class Payload:
    """A pickle payload: unpickling it would run ``touch PATH`` (what a safe loader must refuse)."""

    def __init__(self, path):
        self.path = path

    def __reduce__(self):
        import os

        return os.system, (f"touch {self.path}",)
TRAIN_CONFIG = {"lr": 1e-3, "net": {"width": 8}}


@pytest.fixture(scope="session")
def exported(tmp_path_factory):
    """(the eval-mode RelightNet, the path of its export with ``ema`` smoothing, alpha 0.4)."""
    from relightnet.model.onnx_export import export_onnx

    torch.manual_seed(0)
    net = RelightNet(NET).eval()
    path = tmp_path_factory.mktemp("onnx") / "m.onnx"
    export_onnx(net, path, smoothing="ema", train_config=TRAIN_CONFIG, example_size=32, alpha=0.4)
    return net, path


def make_inputs(b, h, w, seed=0):
    """(image (B, 3, H, W) in [0, 1], mask (B, 1, H, W) binary), reproducible from ``seed``."""
    g = torch.Generator().manual_seed(seed)
    return torch.rand(b, 3, h, w, generator=g), (torch.rand(b, 1, h, w, generator=g) > 0.3).float()
