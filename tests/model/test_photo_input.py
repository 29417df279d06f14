"""Training items framed as the package frames a photo (relightnet.model.photo_input), on generated people."""

import pytest
import torch

from relightnet.checks import InputError
from relightnet.color import linear_to_srgb
from relightnet.model.inference import frame_person
from relightnet.model.network import normalize_input
from relightnet.model.photo_input import FLAW_RADIUS, PhotoInput, as_photo, mask_flaws, morph_mask
from relightnet.model.train_config import TrainConfig
from relightnet.model.training import TrainData, batch_to_input, train

pytestmark = pytest.mark.slow  # a generated dataset


@pytest.fixture(scope="module")
def items(tiny_dataset):
    return TrainData(tiny_dataset, "train", extra=("image_composite",))


def _item(items, i=0):
    return {k: v[i].float() for k, v in items.tensors.items()}


def test_morph_mask_grows_and_shrinks_by_whole_pixels():
    m = torch.zeros(12, 12)
    m[4:8, 4:8] = 1
    assert int(morph_mask(m, 1).sum()) == 36 and int(morph_mask(m, -1).sum()) == 4
    assert torch.equal(morph_mask(m, 0), m)


def test_the_render_framed_at_full_size_is_what_frame_person_gives(items):
    s = _item(items)
    out = as_photo(s, composite=False, scale=1.0, mask_px=0, pad=0.05)
    srgb = linear_to_srgb(s["image"].clamp(0, 1))
    x, mk, _ = frame_person(srgb, s["mask"][0], srgb.shape[-1], 0.05)
    assert torch.allclose(out["input"], normalize_input(x, mk)[0])
    # the targets sit on the same box: the framed mask is the input's, the framed image matches it
    assert torch.equal(out["mask"][0] > 0.5, out["input"][3] > 0.5)
    inside = out["mask"][0] > 0.5
    seen = (out["input"][:3] + 1) / 2
    assert float((seen - linear_to_srgb(out["image"].clamp(0, 1))).abs().mean(0)[inside].mean()) < 0.03
    assert torch.equal(out["light"], s["light"]) and "image_composite" not in out
    assert out["transport"].shape == s["transport"].shape


def test_a_shrunk_composite_keeps_the_targets_at_full_detail(items):
    s = _item(items, 1)
    out = as_photo(s, composite=True, scale=0.5, mask_px=0, pad=0.05)
    assert out["input"].shape == (4, *s["image"].shape[-2:])
    seen, true = out["input"][3] > 0.5, out["mask"][0] > 0.5

    def centre(m):
        ys, xs = torch.nonzero(m, as_tuple=True)
        return torch.stack([ys.float().mean(), xs.float().mean()])

    # the coarse mask and the full-detail targets frame the same person at the same place
    assert float((centre(seen) - centre(true)).abs().max()) < 1.5
    grown = as_photo(s, composite=True, scale=0.5, mask_px=1, pad=0.05)
    seen, true = grown["input"][3] > 0.5, grown["mask"][0] > 0.5
    assert float((seen & true).sum() / true.sum()) > 0.9  # a grown mask covers the person
    assert bool((grown["input"][:3][:, seen] != 0).any())


def test_photo_input_draws_are_seeded_and_a_batch_stacks(items):
    p = PhotoInput(composite=0.5, source_scale=(0.5, 1.0), mask_px=1, prob=0.5)
    a = p(_item(items), torch.Generator().manual_seed(3))
    b = p(_item(items), torch.Generator().manual_seed(3))
    assert all(torch.equal(a[k], b[k]) for k in a)
    batch = items.batch(torch.arange(4), p, [torch.Generator().manual_seed(i) for i in range(4)])
    assert batch_to_input(batch).shape == (4, 4, *items.tensors["image"].shape[-2:])


def test_a_person_the_shrinking_loses_stays_the_render(items):
    s = _item(items)
    s["mask"] = torch.zeros_like(s["mask"])
    s["mask"][0, 3, 3] = 1  # one pixel: gone once the item is shrunk to a fifth
    out = PhotoInput(source_scale=(0.2, 0.2), prob=1.0)(s, torch.Generator().manual_seed(0))
    assert torch.equal(out["mask"], s["mask"]) and out["input"].shape == (4, *s["image"].shape[-2:])
    with pytest.raises(InputError, match="empty"):
        as_photo(s, composite=False, scale=0.2, mask_px=0, pad=0.05)


def test_an_item_larger_than_the_working_size_is_framed_down_as_a_photo(items):
    s = _item(items, 2)
    h = s["image"].shape[-1]
    out = as_photo(s, composite=True, scale=1.0, mask_px=0, pad=0.05, size=h // 2)
    x, mk, _ = frame_person(s["image_composite"] / 255.0, s["mask"][0], h // 2, 0.05)
    assert torch.allclose(out["input"], normalize_input(x, mk)[0])
    assert all(out[k].shape[-2:] == (h // 2, h // 2) for k in ("image", "mask", "albedo", "transport"))
    seen, true = out["input"][3] > 0.5, out["mask"][0] > 0.5
    assert float((seen & true).sum() / (seen | true).sum()) > 0.8  # the truth on the same box
    # an item drawn as a render is framed down too (every item of a batch has the working size)
    render = PhotoInput(prob=0.0, pad=(0.05, 0.05), size=h // 2)(s, torch.Generator().manual_seed(0))
    x, mk, _ = frame_person(linear_to_srgb(s["image"].clamp(0, 1)), s["mask"][0], h // 2, 0.05)
    assert render["input"].shape == (4, h // 2, h // 2) and torch.allclose(render["input"], normalize_input(x, mk)[0])
    s["mask"] = torch.zeros_like(s["mask"])  # no person left to frame (a crop that cut them out): resampled whole
    empty = PhotoInput(prob=1.0, size=h // 2)(s, torch.Generator().manual_seed(0))
    assert empty["input"].shape == (4, h // 2, h // 2) and empty["transport"].shape[-1] == h // 2


def test_mask_flaws_are_holes_and_slivers_near_the_person_and_seeded():
    m = torch.zeros(64, 64)
    m[12:52, 20:44] = 1  # a 40 x 24 person
    near = morph_mask(m, int(FLAW_RADIUS * 40) + 2)
    changed = 0
    for seed in range(40):
        a = mask_flaws(m, torch.Generator().manual_seed(seed))
        assert torch.equal(a, mask_flaws(m, torch.Generator().manual_seed(seed)))  # seeded
        assert set(a.unique().tolist()) <= {0.0, 1.0} and a.any()
        assert not bool((a * (1 - near)).any())  # slivers stay within a flaw's reach of the person
        changed += int((a != m).any())
        grown, cut = bool(((a - m) > 0).any()), bool(((m - a) > 0).any())
        assert grown or cut
    assert changed == 40
    # An empty mask stays empty; a one-pixel person is never removed entirely.
    assert not mask_flaws(torch.zeros(8, 8), torch.Generator().manual_seed(0)).any()
    dot = torch.zeros(8, 8)
    dot[4, 4] = 1
    assert all(mask_flaws(dot, torch.Generator().manual_seed(s)).any() for s in range(10))


def test_flawed_masks_reach_the_input_only(items):
    item = _item(items)
    clean = as_photo(item, True, 0.8, 0, 0.05)
    flawed = as_photo(item, True, 0.8, 0, 0.05, flaws=3)
    assert torch.equal(flawed["mask"], clean["mask"])  # the targets keep the exact mask
    assert not torch.equal(flawed["input"][3], clean["input"][3])  # the input's mask channel has the flaws
    draws = PhotoInput(composite=1.0, mask_flaws=1.0)
    a, b = (draws(item, torch.Generator().manual_seed(5)) for _ in range(2))
    assert torch.equal(a["input"], b["input"])


@pytest.mark.parametrize("bad", [{"composite": 1.5}, {"source_scale": (0.0, 1.0)}, {"source_scale": (0.8, 0.5)},
                                 {"mask_px": -1}, {"mask_px": 1.5}, {"pad": (0.1, 0.05)}, {"prob": -0.1},
                                 {"size": 40}, {"size": True}, {"mask_flaws": 1.5}])
def test_bad_photo_settings_fail_clearly(bad):
    with pytest.raises(InputError, match="photo"):
        PhotoInput(**bad)
    with pytest.raises(InputError, match="photo"):
        TrainConfig(photo={k: list(v) if isinstance(v, tuple) else v for k, v in bad.items()})
    with pytest.raises(InputError, match="photo"):
        TrainConfig(photo={"shrink": 0.5})


def test_training_on_photo_framed_items_runs(tiny_dataset, tmp_path):
    cfg = TrainConfig(steps=2, batch_size=2, warmup=1, log_every=1, checkpoint_every=2, threads=1,
                      net={"width": 8, "max_width": 32, "light_hidden": 32},
                      photo={"composite": 1.0, "source_scale": [0.5, 1.0], "mask_px": 1})
    last = train(cfg, tiny_dataset, tmp_path / "run")
    assert last["step"] == 2 and torch.isfinite(torch.tensor(last["total"]))


def test_a_run_on_larger_items_has_the_photo_size_as_its_working_size(tiny_dataset, tmp_path):
    from relightnet.model.checkpoint import load_checkpoint

    cfg = TrainConfig(steps=1, batch_size=2, warmup=1, log_every=1, checkpoint_every=1, threads=1,
                      net={"width": 8, "max_width": 32, "light_hidden": 32}, augment={},
                      photo={"composite": 0.5, "source_scale": [0.5, 1.0], "prob": 0.5, "size": 16})
    train(cfg, tiny_dataset, tmp_path / "run")
    assert load_checkpoint(tmp_path / "run" / "last.pt")["net_config"]["input_size"] == 16
