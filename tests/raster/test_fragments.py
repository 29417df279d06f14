import math

import pytest
import torch

from relightnet.checks import ShapeError
from relightnet.raster import Fragments


def test_lazy_dense_fields():
    pix = torch.tensor([5, 0, 13])
    frags = Fragments(pix, torch.tensor([2, 0, 1]), torch.tensor([[1.0, 0, 0], [0, 1, 0], [0.2, 0.3, 0.5]]),
                      torch.tensor([0.1, -0.5, 0.9]), (2, 2, 4))
    assert frags.face_id.shape == (2, 2, 4) and frags.bary.shape == (2, 2, 4, 3)
    assert frags.face_id.view(-1)[5] == 2 and frags.face_id.view(-1)[1] == -1
    assert frags.depth.view(-1)[13] == pytest.approx(0.9) and math.isinf(frags.depth.view(-1)[2])
    assert frags.mask.sum() == 3 and frags.mask.view(-1)[13]
    assert frags.pix_batch.tolist() == [0, 0, 1]
    assert frags.face_id is frags.face_id  # cached
    again = Fragments.from_dense(frags.face_id, frags.bary, frags.depth)
    assert torch.equal(again.face_id, frags.face_id) and torch.equal(again.bary, frags.bary)


def test_shape_checks():
    with pytest.raises(ShapeError):
        Fragments(torch.zeros(2, dtype=torch.long), torch.zeros(3, dtype=torch.long), torch.zeros(2, 3),
                  torch.zeros(2), (1, 2, 2))
    with pytest.raises(ShapeError):
        Fragments(torch.zeros(0, dtype=torch.long), torch.zeros(0, dtype=torch.long), torch.zeros(0, 3),
                  torch.zeros(0), (2, 2))


def test_seen_vertices_are_the_vertices_of_the_nearest_faces():
    from relightnet.raster import default_camera, rasterize

    # Two overlapping quads: the nearer one (faces 2, 3) hides the other wholly; vertex 8 is unused.
    far = [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]
    near = [[-0.5, -0.5, 0.5], [0.5, -0.5, 0.5], [0.5, 0.5, 0.5], [-0.5, 0.5, 0.5]]
    verts = torch.tensor(far + near + [[5.0, 5, 5]]) * 0.2 + torch.tensor([0.0, 0.85, 0])
    faces = torch.tensor([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    cam = default_camera(64)
    frags = rasterize(cam.transform(verts), faces, cam.size)
    seen = frags.seen_vertices(faces, 9)
    assert seen.tolist() == torch.unique(faces[torch.unique(frags.pix_face)]).tolist()
    assert seen.tolist() == list(range(8))  # the far quad shows around the near one
    empty = Fragments(torch.zeros(0, dtype=torch.long), torch.zeros(0, dtype=torch.long), torch.zeros(0, 3),
                      torch.zeros(0), (1, 2, 2))
    assert empty.seen_vertices(faces, 9).numel() == 0


def test_locate_and_frame_pixels():
    """locate: a pixel's position in the compact fields (−1 off the mesh); frame_pixels: the frame's
    (batch, row, column) of a window's pixel."""
    from relightnet.raster import Window

    pix = torch.tensor([5, 0, 13])
    frags = Fragments(pix, torch.tensor([2, 0, 1]), torch.zeros(3, 3), torch.zeros(3), (2, 2, 4),
                      Window(3, 1, 2, 4, (6, 9)))
    assert frags.locate(torch.tensor([13, 1, 0, 5, 15])).tolist() == [2, -1, 1, 0, -1]
    b, row, col = frags.frame_pixels(torch.tensor([0, 5, 13]))
    assert b.tolist() == [0, 0, 1] and row.tolist() == [3, 4, 4] and col.tolist() == [1, 2, 2]
    assert frags.region == frags.window
    whole = Fragments(pix, torch.tensor([2, 0, 1]), torch.zeros(3, 3), torch.zeros(3), (2, 2, 4))
    assert whole.region == Window.full((2, 4)) and whole.frame_pixels(pix)[2].tolist() == [1, 0, 1]
    empty = Fragments(pix[:0], pix[:0], torch.zeros(0, 3), torch.zeros(0), (1, 2, 2))
    assert empty.locate(torch.tensor([0, 3])).tolist() == [-1, -1]
    with pytest.raises(ShapeError, match="window"):
        Fragments(pix, torch.tensor([2, 0, 1]), torch.zeros(3, 3), torch.zeros(3), (2, 2, 4),
                  Window(0, 0, 3, 4, (6, 9)))
