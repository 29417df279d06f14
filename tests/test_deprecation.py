"""relightnet.deprecation: the one helper of the deprecation policy."""

import warnings

import pytest

from relightnet.deprecation import deprecated, warn_deprecated


def test_warn_deprecated_names_since_removal_and_replacement():
    with pytest.warns(DeprecationWarning, match=r"^old\(\) is deprecated since relightnet 0\.1\.0 and is removed in "
                      r"0\.2\.0: use new\(\)$"):
        warn_deprecated("old()", "0.1.0", "0.2.0", "new()")


def test_deprecated_wraps_a_function_and_points_at_its_caller():
    @deprecated("0.1.0", "0.2.0", "twice()")
    def double(x):
        """Twice x."""
        return 2 * x

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert double(3) == 6
    (w,) = caught
    assert w.category is DeprecationWarning and w.filename == __file__  # the caller's line, not the helper's
    assert "double is deprecated since relightnet 0.1.0" in str(w.message) and "use twice()" in str(w.message)
    assert double.__name__ == "double" and "removed in 0.2.0" in double.__doc__ and "Twice x." in double.__doc__
