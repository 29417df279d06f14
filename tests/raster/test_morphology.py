"""relightnet.raster.morphology: binary erosion of masks."""

import pytest
import torch

from relightnet.checks import InputError, ShapeError
from relightnet.raster import erode


def test_erode_is_min_pooling_over_a_square():
    m = torch.zeros(1, 1, 9, 9)
    m[..., 2:7, 2:7] = 1
    e = erode(m, 1)
    assert e.sum() == 9 and e[..., 3:6, 3:6].all()  # a 5x5 square loses its 1-pixel rim
    assert erode(m, 2).sum() == 1 and torch.equal(erode(m, 0), m)
    assert erode(torch.ones(2, 1, 4, 4), 1).sum() == 32  # the image border does not erode


def test_erode_refuses_a_negative_radius_and_a_wrong_shape():
    with pytest.raises(InputError, match="radius"):
        erode(torch.ones(1, 1, 4, 4), -1)
    with pytest.raises(ShapeError, match="mask"):
        erode(torch.ones(1, 4, 4), 1)
