import pytest
import torch

from relightnet.checks import (
    InputError,
    RelightError,
    ShapeError,
    check_dtype,
    check_finite,
    check_sh_count,
    check_shape,
    check_unit,
    sh_order_from_count,
)


def test_check_shape_message_as_specified():
    with pytest.raises(ShapeError) as e:
        check_shape(torch.zeros(2, 16), ["B", "K", "3"], name="light")
    assert str(e.value) == "light: expected (B, K, 3), got (2, 16)"
    assert isinstance(e.value, RelightError) and isinstance(e.value, ValueError)


def test_check_shape_binds_names_and_ellipsis():
    assert check_shape(torch.zeros(2, 9, 3), ["B", "K", 3]) == {"B": 2, "K": 9}
    assert check_shape(torch.zeros(4, 5, 6, 3), ["...", 3]) == {}
    assert check_shape(torch.zeros(2, 9, 9), ["B", "K", "K"]) == {"B": 2, "K": 9}
    with pytest.raises(ShapeError, match=r"x: expected \(B, K, K\), got \(2, 9, 8\)"):
        check_shape(torch.zeros(2, 9, 8), ["B", "K", "K"], name="x")
    with pytest.raises(ShapeError, match="K=9"):
        check_shape(torch.zeros(16, 3), ["K", 3], name="sh", dims={"K": 9})
    with pytest.raises(ShapeError):
        check_shape(torch.zeros(3), ["...", "H", 3])


def test_value_checks():
    check_finite(torch.ones(3))
    with pytest.raises(InputError, match="light: contains NaN"):
        check_finite(torch.tensor([1.0, float("inf")]), "light")
    check_unit(torch.tensor([[0.0, 0.6, 0.8]]))
    with pytest.raises(InputError, match="normals: expected unit"):
        check_unit(torch.tensor([[0.0, 0.0, 2.0]]), "normals")
    with pytest.raises(InputError, match="expected dtype in \\(float32\\), got int64"):
        check_dtype(torch.ones(2, dtype=torch.int64), [torch.float32])


def test_sh_counts():
    assert [sh_order_from_count(k) for k in (1, 4, 9, 16, 25)] == [0, 1, 2, 3, 4]
    with pytest.raises(ShapeError, match="got 8"):
        sh_order_from_count(8)
    assert check_sh_count(torch.zeros(5, 9, 3)) == 2
    with pytest.raises(ShapeError):
        check_sh_count(torch.zeros(10, 3), "light")
