import torch

from relightnet.raster.clip import GUARD_BAND, clip_triangles, outcodes, plane_distances


def test_clipped_pieces_lie_inside_and_keep_orientation():
    g = torch.Generator().manual_seed(0)
    tri = torch.randn(50, 3, 4, generator=g, dtype=torch.float64) * 3
    tri[..., 3] = tri[..., 3].abs() * 2 - 1  # some vertices behind the camera (w < 0)
    pieces, ids = clip_triangles(tri, torch.arange(50))
    assert pieces.shape[0] > 0 and pieces.shape[1:] == (3, 4)
    d = plane_distances(pieces)[..., :6]
    assert (d >= -1e-9).all()
    assert (pieces[..., 3] > 0).all()
    # each piece lies in its source triangle's plane (clip-space affine span)
    for p, i in zip(pieces, ids, strict=True):
        sol = torch.linalg.lstsq(tri[i].T, p.T).solution
        assert torch.allclose(tri[i].T @ sol, p.T, atol=1e-8)
        assert torch.allclose(sol.sum(0), torch.ones(3, dtype=torch.float64), atol=1e-8)


def test_shared_edge_is_clipped_identically():
    a, b = torch.tensor([0.5, 0.2, 0.0, 1.0]), torch.tensor([-0.3, 0.1, 0.0, -1.0])  # b behind
    c1, c2 = torch.tensor([0.9, -0.8, 0.0, 1.0]), torch.tensor([-0.9, 0.9, 0.0, 2.0])
    t = torch.stack([torch.stack([a, b, c1]), torch.stack([b, a, c2])]).double()
    pieces, ids = clip_triangles(t, torch.arange(2))
    verts = [set(map(tuple, pieces[ids == k].reshape(-1, 4).tolist())) for k in range(2)]
    shared = verts[0] & verts[1]
    assert len(shared) == 2  # a itself and the identical near-plane point on edge a-b


def test_outcodes_bits():
    g = GUARD_BAND
    pts = torch.tensor([[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, -2.0, 1.0], [3 * g, 0.0, 0.0, 1.0]])
    codes = outcodes(pts)
    assert codes[0] == 0
    assert codes[1] & 1  # behind the near plane
    assert codes[2] & (1 << 2) and codes[2] & (1 << 6)  # beyond +x guard band and viewport
