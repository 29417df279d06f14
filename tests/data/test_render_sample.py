"""The generator's core: render_clip (stills and clips from a seed sequence) and clip_geometry."""

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.data.config import SynthConfig, sample_seed
from relightnet.data.generate import generate_sample, generate_sequence, prepare_assets
from relightnet.data.render_sample import CLIP_KEY, STREAMS, ClipGeometry, clip_geometry, render_clip
from relightnet.raster import rasterize

CFG = SynthConfig(res=32, n_dirs=8)
T = 2


pytestmark = pytest.mark.usefixtures("one_thread")  # tests/data/conftest.py


@pytest.fixture(scope="module")
def assets(anny_body):
    return prepare_assets(anny_body, texture_size=64)


def test_render_clip_is_the_generated_still_and_clip(assets):
    still = render_clip(CFG, "train", 1, sample_seed(CFG, "train", 1), assets, None)
    ref = generate_sample(CFG, "train", 1, assets)
    assert still.meta == ref.meta and still.meta["kind"] == "still" and still.arrays["image"].shape == (32, 32, 3)
    assert all(still.arrays[k].tobytes() == v.tobytes() for k, v in ref.arrays.items())
    ss = sample_seed(CFG, "train", 1)
    clip = render_clip(CFG, "train", 1, np.random.SeedSequence(ss.entropy, spawn_key=(CLIP_KEY,)), assets, T)
    seq = generate_sequence(CFG, "train", 1, T, assets)
    assert clip.meta == seq.meta and clip.arrays["image"].shape == (T, 32, 32, 3) and clip.meta["n_frames"] == T
    assert all(clip.arrays[k].tobytes() == v.tobytes() for k, v in seq.arrays.items())
    assert len(STREAMS) == 9 and STREAMS[0] == "body" and STREAMS[-1] == "garments"


def test_evaluation_clips_switch_half_way(assets):
    cfg = CFG.replace(res=16, clip_lights="switch")
    m = render_clip(cfg, "val", 0, np.random.SeedSequence(7), assets, 4).meta
    assert m["switch_frames"] == [2]
    assert [f["light"] for f in m["frames"]] == [0, 0, 1, 1]
    assert len({f["rotation_deg"] for f in m["frames"][:2]}) == 1 and len({f["level"] for f in m["frames"][:2]}) == 1
    m = render_clip(cfg.replace(clip_lights="constant"), "val", 0, np.random.SeedSequence(7), assets, 4).meta
    assert m["switch_frames"] in (None, []) and {f["light"] for f in m["frames"]} == {0}


def test_clip_geometry_reproduces_the_generated_clip(assets):
    clip = generate_sequence(CFG, "test", 0, T, assets).arrays
    geo = clip_geometry(CFG, "test", 0, T, assets)
    assert isinstance(geo, ClipGeometry)
    assert geo.verts.shape[0] == T and geo.verts.shape == geo.normals.shape and geo.faces.shape[1] == 3
    torch.testing.assert_close(geo.R @ geo.R.T, torch.eye(3, dtype=torch.float64))
    assert geo.world_to_camera.shape == (4, 4)
    for t in range(T):
        fr = rasterize(geo.camera.transform(geo.verts[t]), geo.faces, geo.camera.size)
        np.testing.assert_array_equal(fr.mask[0].float().numpy(), clip["mask"][t])
    # A still's geometry is a single frame.
    assert clip_geometry(CFG, "test", 0, None, assets).verts.shape[0] == 1
    with pytest.raises(InputError, match="n_frames"):
        clip_geometry(CFG, "test", 0, 0)
