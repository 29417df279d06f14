"""The real-people encoder (model.pose_features): a zero start, frozen weights out of the state dict."""

import pytest
import torch

from relightnet.checks import InputError
from relightnet.model import NetConfig, RelightNet, normalize_input


def test_pose_encoder_network_starts_as_the_plain_network_and_saves_only_what_trains():
    from relightnet.model.network import ENCODERS

    assert ENCODERS == ("own", "pose")
    cfg = NetConfig(width=8, max_width=32, light_hidden=32, encoder="pose")
    net = RelightNet(cfg).eval()
    plain = RelightNet(NetConfig(width=8, max_width=32, light_hidden=32)).eval()
    own = {k: v for k, v in net.state_dict().items() if not k.startswith("pose.")}
    plain.load_state_dict(own)
    x = normalize_input(torch.rand(2, 3, 32, 48), torch.ones(2, 1, 32, 48))
    with torch.no_grad():  # zero projections: the pose features add nothing yet
        torch.testing.assert_close(net(x).transport, plain(x).transport)
    frozen = [k for k, p in net.named_parameters() if not p.requires_grad]
    assert frozen and all(k.startswith("pose.encoder.") for k in frozen)
    assert not set(frozen) & set(net.state_dict())  # the package's own file, not the checkpoint's
    again = RelightNet(cfg)
    again.load_state_dict(net.state_dict())  # frozen weights come back from the file
    net.train()
    p = net(x)
    (p.transport.mean() + p.light.mean()).backward()
    assert all(q.grad is not None for q in net.pose.proj.parameters())
    assert all(q.grad is None for q in net.pose.encoder.parameters())


@pytest.mark.slow
def test_pose_encoder_can_train_its_last_stage():
    net = RelightNet(NetConfig(width=8, max_width=32, light_hidden=32, encoder="pose", encoder_train_after=8))
    trained = {k for k, p in net.named_parameters() if p.requires_grad and k.startswith("pose.encoder.")}
    assert trained and trained <= set(net.state_dict())
    with pytest.raises(InputError, match="encoder_train_after"):
        NetConfig(encoder="pose", encoder_train_after=3)
    with pytest.raises(InputError, match="encoder"):
        NetConfig(encoder="resnet")
