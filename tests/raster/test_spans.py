import torch

from relightnet.raster.spans import KEY_MAX, ZBuffer, chunks


def test_chunks_cover_everything_in_order():
    counts = torch.tensor([3, 0, 5, 1, 7, 2, 0, 4])
    parts = chunks(counts, limit=6)
    assert parts[0][0] == 0 and parts[-1][1] == 8
    assert all(a < b for a, b in parts) and all(p[1] == q[0] for p, q in zip(parts[:-1], parts[1:], strict=True))
    assert chunks(counts, limit=100) == [(0, 8)]
    assert chunks(torch.zeros(0, dtype=torch.long)) == []
    big = chunks(torch.tensor([50, 1, 1]), limit=10)
    assert big[0] == (0, 1) and big[-1][1] == 3


def test_zbuffer_keeps_nearest_and_finds_winners():
    for n_pix in (10, 3):  # 3: more candidates than pixels → winners by scanning the buffer
        zb = ZBuffer(n_pix, n_tri=4, device="cpu")
        pix = torch.tensor([0, 1, 2, 1, 2])
        tid = torch.tensor([0, 1, 2, 3, 0])
        depth = torch.tensor([0.5, 0.7, 0.2, 0.1, 0.2], dtype=torch.float64) + 2
        key = (depth.view(torch.int64) & -(1 << zb.fbits)) | tid
        zb.add(pix, key)
        win_pix, win_t = zb.winners()
        got = dict(zip(win_pix.tolist(), win_t.tolist(), strict=True))
        assert got == {0: 0, 1: 3, 2: 0}  # equal depths: the lower triangle index wins
        assert (zb.buf[3:] == KEY_MAX).all()
