import torch

from relightnet.temporal.plot import light_curves_png

PNG = b"\x89PNG\r\n\x1a\n"


def test_light_curves_png_all_parts_and_dc_only():
    g = torch.Generator().manual_seed(0)
    raw = torch.randn(20, 9, 3, generator=g)
    flags = torch.zeros(20, dtype=torch.bool)
    flags[7] = True
    full = light_curves_png(raw, raw * 0.5, truth=raw * 0.4, outliers=flags, switches=flags, title="t")
    assert full.startswith(PNG) and len(full) > 5000
    dc = light_curves_png(None, torch.rand(5, 1, 3))  # order 0: one panel, no raw points
    assert dc.startswith(PNG) and len(dc) < len(full)
