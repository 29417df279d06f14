import pytest
import torch

from relightnet.body import default_albedo
from relightnet.body.albedo import ANNY_PARTS, REGIONS, anny_part_labels, region_labels, skin_color, vertex_to_texture
from relightnet.checks import InputError


@pytest.fixture(scope="module")
def regions(anny_body):
    return region_labels(anny_body)


@pytest.fixture(scope="module")
def parts(anny_body):
    return anny_part_labels(anny_body)


def test_part_labels_from_anny_segmentation(anny_body, parts):
    assert parts.shape == (anny_body.num_verts,) and parts.dtype == torch.int64
    assert torch.bincount(parts, minlength=len(ANNY_PARTS)).min() > 0  # every shipped part is found
    v = anny_body().verts[0]
    for side, sign in (("L", 1), ("R", -1)):
        for p in ("hand", "foot"):
            sel = parts == ANNY_PARTS.index(f"{p}.{side}")
            assert (sign * v[sel, 0] > 0.1).all()
    assert v[parts == ANNY_PARTS.index("head"), 1].min() > 1.3


def test_region_labels_cover_all_regions_sensibly(anny_body, regions, parts):
    assert regions.shape == (anny_body.num_verts,) and regions.dtype == torch.int64
    counts = torch.bincount(regions, minlength=len(REGIONS))
    assert len(counts) == len(REGIONS) and (counts > 100).all()
    o = anny_body()
    v, J = o.verts[0], dict(zip(o.joint_names, o.joints[0], strict=True))
    R = {r: i for i, r in enumerate(REGIONS)}
    assert regions[v[:, 1].argmax()] == R["hair"]  # top of the head
    assert (regions[(parts == ANNY_PARTS.index("hand.L")) | (parts == ANNY_PARTS.index("hand.R"))] == R["skin"]).all()
    assert (regions[(parts == ANNY_PARTS.index("foot.L")) | (parts == ANNY_PARTS.index("foot.R"))] == R["shoes"]).all()
    chest = v[:, 2] + 10 * ((v[:, 1] - J["spine01"][1]).abs() > 0.03) + 10 * (v[:, 0].abs() > 0.03)
    assert regions[chest.argmin()] == R["top"]  # back of the chest
    knee = (v - J["lowerleg01.L"]).norm(dim=-1).argmin()
    assert regions[knee] == R["bottom"]
    nose = v[v[:, 1] > J["neck03"][1]][:, 2].argmax()
    assert regions[v[:, 1] > J["neck03"][1]][nose] == R["skin"]
    with pytest.raises(InputError, match="sleeves"):
        region_labels(anny_body, sleeves="puffy")


def test_clothing_lengths(anny_body, regions):
    top, bottom = REGIONS.index("top"), REGIONS.index("bottom")
    long = region_labels(anny_body, sleeves="long", legs="shorts", hair="none")
    assert (long == top).sum() > (regions == top).sum() + 300
    assert (long == bottom).sum() < (regions == bottom).sum() - 300
    assert (long == REGIONS.index("hair")).sum() == 0


def test_default_albedo_ranges_and_texture(anny_body, regions):
    a = default_albedo(anny_body, regions=regions)
    assert a.vertex.shape == (anny_body.num_verts, 3) and a.vertex.dtype == torch.float32
    assert a.texture.shape == (512, 512, 3) and a.texture.dtype == torch.float32
    for x in (a.vertex, a.texture):
        assert x.min() >= 0.02 and x.max() <= 0.9
    skin = skin_color(0.3)
    assert torch.allclose(a.vertex[regions == REGIONS.index("skin")].median(0).values, skin)
    assert default_albedo(anny_body, regions=regions, texture_size=None).texture is None
    red = default_albedo(anny_body, regions=regions, texture_size=None, colors={"top": (0.8, 0.05, 0.05)})
    assert torch.allclose(red.vertex[regions == REGIONS.index("top")][0], torch.tensor([0.8, 0.05, 0.05]))
    with pytest.raises(InputError, match="unknown key 'cape'"):
        default_albedo(anny_body, regions=regions, colors={"cape": (1, 1, 1)})


def test_skin_tone():
    lum = [float(skin_color(t) @ torch.tensor([0.2126, 0.7152, 0.0722])) for t in (0.0, 0.25, 0.5, 0.75, 1.0)]
    assert all(a > b for a, b in zip(lum, lum[1:], strict=False))
    assert all(((skin_color(t) >= 0.02) & (skin_color(t) <= 0.9)).all() for t in (0.0, 1.0))
    with pytest.raises(InputError, match="skin_tone"):
        skin_color(1.5)


def test_texture_holds_the_vertex_values_at_their_uvs(anny_body, regions):
    size = 256
    tex = vertex_to_texture(anny_body, regions[:, None].float(), size)[..., 0]
    uv, ft, f = anny_body.uv, anny_body.uv_faces.reshape(-1), anny_body.faces.reshape(-1)
    col = (uv[ft, 0] * size).long().clamp(0, size - 1)
    row = ((1 - uv[ft, 1]) * size).long().clamp(0, size - 1)
    agree = (tex[row, col] == regions[f].float()).float().mean()
    assert agree > 0.9  # nearest-UV painting; region borders may shift by a texel
