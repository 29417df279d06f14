import sys

import pytest

from relightnet.checks import InputError
from relightnet.distributed import connect
from relightnet.distributed.cluster import import_ray, one_line


def test_without_ray_a_one_line_error_says_how_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # as if ray were not installed
    with pytest.raises(InputError, match=r"^--ray: the 'ray' package is not importable .*'relightnet\[ray\]'$"):
        import_ray()
    with pytest.raises(InputError, match="not importable"), connect():
        pass


class _TaskError(Exception):
    def __init__(self, cause):
        super().__init__("Traceback (most recent call last):\n  ...\nOSError: disk full")
        self.cause = cause


def test_one_line():
    assert one_line(ValueError("bad\nmore")) == "ValueError: bad"
    assert one_line(_TaskError(OSError("disk full"))) == "OSError: disk full"  # a Ray task error: its cause
    assert one_line(RuntimeError()) == "RuntimeError"
