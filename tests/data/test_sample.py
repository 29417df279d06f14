"""The generator's per-body precomputation (prepare_assets, assets_for, SynthAssets memos) and Sample."""

import dataclasses

import numpy as np
import pytest

from relightnet.body.albedo import REGIONS
from relightnet.checks import InputError
from relightnet.data.sample import Sample, SynthAssets, assets_for, prepare_assets


@pytest.fixture(scope="module")
def assets(anny_body):
    return prepare_assets(anny_body, texture_size=64)


def test_prepare_assets_builds_the_atlas(assets, anny_body):
    assert isinstance(assets, SynthAssets) and assets.body is anny_body
    assert assets.atlas.size == 64 and assets.atlas.texel_vertex.shape == (64 * 64,)
    assert assets.atlas.vertex_texel.shape == (anny_body.num_verts,)
    assert assets.regions == {} and assets.envmaps == {}  # filled on use
    with pytest.raises(InputError, match="body: expected an AnnyBody, got str"):
        prepare_assets("anny")


def test_region_field_and_envmap_are_memoised(assets, anny_body):
    f = assets.region_field("short", "long", "short")
    assert f.shape[0] == anny_body.num_verts and f.shape[1] <= len(REGIONS) + 1
    assert np.isfinite(f).all() and assets.region_field("short", "long", "short") is f
    assert set(assets.regions) == {("short", "long", "short")}
    env = assets.envmap("studio")
    assert env.ndim == 3 and env.shape[-1] == 3 and bool((env >= 0).all())
    assert assets.envmap("studio") is env


def test_assets_for_reuses_per_body(assets, anny_body):
    assert assets_for(assets) is assets
    a = assets_for(anny_body)
    assert isinstance(a, SynthAssets) and a.body is anny_body and assets_for(anny_body) is a
    with pytest.raises(InputError, match="body: expected None, an AnnyBody or SynthAssets, got int"):
        assets_for(3)


def test_sample_holds_arrays_and_meta():
    s = Sample({"image": np.zeros((2, 2, 3), np.float32)}, {"kind": "still"})
    assert s.meta["kind"] == "still" and s.arrays["image"].shape == (2, 2, 3)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.meta = {}
