import copy
import json

import numpy as np
import pytest
import torch

from relightnet.body.albedo import REGIONS, region_labels
from relightnet.checks import InputError
from relightnet.data.textures import (
    ALBEDO_MAX,
    ALBEDO_MIN,
    PATTERNS,
    paint_albedo,
    sample_outfit,
    uv_atlas,
    vertex_albedo,
)
from relightnet.raster import texture

SIZE = 128


@pytest.fixture(scope="module")
def atlas(anny_body):
    return uv_atlas(anny_body, SIZE)


@pytest.fixture(scope="module")
def regions(anny_body):
    return region_labels(anny_body, "long", "long", "short").numpy()


def test_atlas_tables(anny_body, atlas):
    V = anny_body.num_verts
    assert atlas.size == SIZE
    assert atlas.texel_vertex.shape == (SIZE * SIZE,) and 0 <= atlas.texel_vertex.min() and atlas.texel_vertex.max() < V
    assert atlas.vertex_texel.shape == (V,) and atlas.vertex_texel.max() < SIZE * SIZE
    assert atlas.parts.shape == (V,)
    rest = anny_body().verts[0].detach()
    lo, hi = rest.amin(0).numpy(), rest.amax(0).numpy()
    assert np.isfinite(atlas.texel_pos).all()
    assert (atlas.texel_pos >= lo - 1e-4).all() and (atlas.texel_pos <= hi + 1e-4).all()
    # A texel's position is near its vertex (within a triangle's size).
    d = np.linalg.norm(atlas.texel_pos - rest.numpy()[atlas.texel_vertex], axis=1)
    assert np.percentile(d, 99) < 0.03


def test_vertex_texel_lies_in_a_triangle_of_that_vertex(anny_body, atlas):
    # Sampling a per-vertex id texture at each vertex's texel gives a vertex of a face containing it:
    # check instead that the texel's nearest vertex is within one ring (close in space).
    rest = anny_body().verts[0].detach().numpy()
    near = atlas.texel_vertex[atlas.vertex_texel]
    d = np.linalg.norm(rest[near] - rest, axis=1)
    assert np.percentile(d, 95) < 0.03


def test_outfit_is_json_and_deterministic():
    a = sample_outfit(np.random.default_rng(4))
    b = sample_outfit(np.random.default_rng(4))
    assert a == b
    json.dumps(a)
    assert a["top"]["pattern"] in PATTERNS and a["sleeves"] in ("none", "short", "elbow", "long")


def test_outfits_vary():
    rng = np.random.default_rng(0)
    outfits = [sample_outfit(rng) for _ in range(60)]
    assert {o["top"]["pattern"] for o in outfits} == set(PATTERNS)
    tones = [o["skin_tone"] for o in outfits]
    assert min(tones) < 0.15 and max(tones) > 0.75
    assert len({o["sleeves"] for o in outfits}) == 4 and len({o["legs"] for o in outfits}) == 3


@pytest.mark.parametrize("seed", range(4))
def test_painted_albedo_range_and_regions(atlas, regions, seed):
    o = sample_outfit(np.random.default_rng(seed))
    o["hair"] = [0.05, 0.03, 0.02]
    tex = paint_albedo(atlas, regions, o)
    assert tex.shape == (SIZE, SIZE, 3) and tex.dtype == torch.float32
    assert tex.min() >= np.float32(ALBEDO_MIN) and tex.max() <= np.float32(ALBEDO_MAX)
    # Per-region mean colour follows the outfit (skin: its tone; plain garments: their colour).
    reg = regions[atlas.texel_vertex]
    flat = tex.reshape(-1, 3).numpy()
    skin = flat[(reg == REGIONS.index("skin")) & (atlas.parts[atlas.texel_vertex] <= 3)]
    assert np.allclose(np.median(skin, 0), np.clip(o["skin"], ALBEDO_MIN, ALBEDO_MAX), rtol=0.1, atol=0.01)
    assert np.allclose(np.median(flat[reg == REGIONS.index("hair")], 0), o["hair"], rtol=0.2, atol=0.01)
    assert paint_albedo(atlas, regions, o).equal(tex)  # deterministic


def test_patterns_use_both_colours(atlas, regions):
    o = sample_outfit(np.random.default_rng(7))
    top = REGIONS.index("top")
    sel = regions[atlas.texel_vertex] == top
    for pattern in PATTERNS:
        g = copy.deepcopy(o)
        g["top"].update(pattern=pattern, color=[0.8, 0.1, 0.1], color2=[0.05, 0.05, 0.6], fabric=0.0,
                        period=0.05, n_blobs=30, blob_radius=0.06)
        t = paint_albedo(atlas, regions, g).reshape(-1, 3).numpy()[sel]
        second = (t[:, 2] > t[:, 0]).mean()  # texels closer to the second colour
        if pattern == "plain":
            assert second == 0
        else:
            assert 0.03 < second < 0.97, pattern


def test_sleeve_variants_change_the_top_region(anny_body, atlas):
    short = region_labels(anny_body, "short", "long", "short").numpy()
    long = region_labels(anny_body, "long", "long", "short").numpy()
    o = sample_outfit(np.random.default_rng(1))
    o["top"].update(pattern="plain", color=[0.1, 0.6, 0.1], fabric=0.0)
    a, b = paint_albedo(atlas, short, o), paint_albedo(atlas, long, o)
    green = lambda t: int(((t[..., 1] > 0.4) & (t[..., 0] < 0.2)).sum())  # noqa: E731
    assert green(b) > green(a) * 1.1  # long sleeves cover more texels


def test_vertex_albedo_and_texture_lookup(anny_body, atlas, regions):
    o = sample_outfit(np.random.default_rng(2))
    tex = paint_albedo(atlas, regions, o)
    va = vertex_albedo(atlas, tex)
    assert va.shape == (anny_body.num_verts, 3)
    # The texture sampled at a vertex's UVs is close to the per-vertex value for most vertices.
    uv_idx = anny_body.uv_faces.reshape(-1)
    vid = anny_body.faces.reshape(-1)
    uv = anny_body.uv[uv_idx][None, None]  # (1, 1, N, 2)
    s = texture(tex.permute(2, 0, 1)[None], uv, filter="nearest")[0, 0]
    assert (s - va[vid]).abs().amax(1).median() < 0.05


def test_bad_size_raises(anny_body):
    with pytest.raises(InputError):
        uv_atlas(anny_body, 4)


def test_region_field_smooths_but_keeps_the_labels(anny_body, atlas, regions):
    from relightnet.data.textures import region_field, texel_regions

    field = region_field(anny_body.faces.numpy(), regions)
    assert field.shape == (anny_body.num_verts, len(REGIONS)) and field.dtype == np.float32
    assert np.allclose(field.sum(1), 1, atol=1e-5) and field.min() >= 0
    assert (field.argmax(1) == regions).mean() > 0.97  # only boundary vertices can change
    assert ((field.max(1) < 1 - 1e-6) & (field.max(1) > 0)).any()  # boundaries are blurred
    hard, soft = texel_regions(atlas, regions), texel_regions(atlas, field)
    assert hard.shape == soft.shape == (SIZE * SIZE,)
    assert (hard == soft).mean() > 0.95
    tex = paint_albedo(atlas, field, sample_outfit(np.random.default_rng(0)))
    assert tex.shape == (SIZE, SIZE, 3)
