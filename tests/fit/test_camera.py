import math

import torch

from relightnet.fit import default_intrinsics, exif_intrinsics
from relightnet.fit.camera import project_points


def test_default_fov_and_projection():
    fx, fy, cx, cy = default_intrinsics((480, 640), 60.0)
    assert abs(fx - 320 / math.tan(math.radians(30))) < 1e-9 and fx == fy and (cx, cy) == (320, 240)
    # a point at the edge of the field of view lands on the image border
    p = torch.tensor([[math.tan(math.radians(30)), 0.0, -1.0], [0.0, 0.5, -2.0]])
    uv = project_points(p, (fx, fy, cx, cy))
    torch.testing.assert_close(uv[0], torch.tensor([640.0, 240.0]))
    torch.testing.assert_close(uv[1], torch.tensor([320.0, 240.0 - fy * 0.25]))


def test_exif_focal_length(tmp_path):
    from PIL import Image

    img = Image.new("RGB", (400, 300))
    exif = Image.Exif()
    exif.get_ifd(0x8769)[0xA405] = 26  # 26 mm-equivalent lens
    img.save(tmp_path / "a.jpg", exif=exif)
    img.save(tmp_path / "b.jpg")
    fx, fy, cx, cy = exif_intrinsics(tmp_path / "a.jpg", (300, 400))
    assert abs(fx - 26 / 36 * 400) < 1e-6 and (cx, cy) == (200, 150)
    assert exif_intrinsics(tmp_path / "b.jpg", (300, 400)) is None
