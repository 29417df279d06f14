"""Where Anny's cache is found: $ANNY_CACHE_DIR, else the checkout's .cache/anny that make filled."""

from __future__ import annotations

from relightnet.body import cache


def test_cache_dir_rule(tmp_path, monkeypatch):
    filled = tmp_path / "anny"
    monkeypatch.setattr(cache, "PROJECT_CACHE", filled)
    monkeypatch.delenv("ANNY_CACHE_DIR", raising=False)
    assert cache.anny_cache_dir() is None  # nothing filled: anny's own default
    filled.mkdir()
    (filled / ".filled").touch()  # what make leaves when it has filled the cache
    assert cache.anny_cache_dir() == str(filled)
    monkeypatch.setenv("ANNY_CACHE_DIR", str(tmp_path / "mine"))
    assert cache.anny_cache_dir() == str(tmp_path / "mine")


def test_the_installed_package_points_at_the_checkouts_cache():
    assert cache.PROJECT_CACHE.parent.parent == cache.Path(cache.__file__).resolve().parents[2]
    assert (cache.PROJECT_CACHE.parents[1] / "pyproject.toml").is_file()  # the checkout make installs from
