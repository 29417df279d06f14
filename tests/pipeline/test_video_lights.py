"""The light of a video: per-frame estimates (estimate_video_evidence), the reusable side file."""

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.model import NetConfig, RelightNet
from relightnet.pipeline.video_lights import (
    VideoEstimates,
    estimate_video_evidence,
    estimate_video_lights,
    lights_fingerprint,
    read_light_estimates,
    write_video_lights,
)
from relightnet.sh.light_solve import Evidence


@pytest.mark.slow
def test_estimates_of_a_video_per_frame(masked_clip, tmp_path):
    torch.manual_seed(0)
    net = RelightNet(NetConfig(width=4, max_width=8, levels=2, light_hidden=8, mask_head=False, input_size=32)).eval()
    video, masks = masked_clip(tmp_path, n=3)
    raw, ev, prior, colour = estimate_video_evidence(net, video, masks, progress=False)
    assert raw.shape == (3, 9, 3) and torch.isfinite(raw).all() and ev is None and prior is None
    assert colour.shape == (3, 3) and colour.dtype == torch.float64 and (colour > 0).all()
    torch.testing.assert_close(estimate_video_lights(net, video, masks, progress=False), raw)
    assert not torch.equal(raw[0], raw[2])  # the block moves: each frame has its own estimate
    with pytest.raises(InputError, match="no mask head"):
        estimate_video_evidence(net, video, None, progress=False, mask_source="head")


def test_side_file_round_trip_and_fingerprint(masked_clip, tmp_path):
    video, masks = masked_clip(tmp_path, n=3)
    fp = lights_fingerprint(video, masks, "torch:a")
    assert fp != lights_fingerprint(video, masks, "torch:b") and fp != lights_fingerprint(video, None, "torch:a")
    g = torch.Generator().manual_seed(0)
    raw = torch.randn(3, 9, 3, generator=g)
    ev = Evidence(torch.randn(3, 3, 9, 9, generator=g), torch.randn(3, 3, 9, generator=g))
    prior = torch.randn(3, 9, 3, generator=g)
    colour = torch.rand(3, 3, generator=g, dtype=torch.float64) + 0.1
    flags = torch.tensor([False, True, False])
    side, plot = tmp_path / "out" / "o.lights.npz", tmp_path / "out" / "o.lights.png"
    write_video_lights(side, plot, raw * 0.5, fp, VideoEstimates(raw, ev, prior, colour), outliers=flags,
                       switches=~flags, smoothing="pooled", title="t")
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    got = read_light_estimates(side, fp)
    assert got is not None
    r, e, p, c = got
    assert torch.equal(r, raw) and torch.equal(e[0], ev[0]) and torch.equal(e[1], ev[1]) and torch.equal(p, prior)
    assert torch.equal(c, colour)
    assert np.load(side)["smoothing"] == "pooled"
    # a file of estimates without the frames' colours (an older one) is estimated again
    write_video_lights(side, plot, raw * 0.5, fp, VideoEstimates(raw, ev, prior), outliers=flags, switches=~flags)
    assert "colour" not in np.load(side) and read_light_estimates(side, fp) is None
    assert read_light_estimates(side, lights_fingerprint(video, masks, "other")) is None  # other inputs
    assert read_light_estimates(tmp_path / "none.npz", fp) is None
    side.write_bytes(b"damaged")
    assert read_light_estimates(side, fp) is None
