"""Person masks on real pixels: scikit-image's astronaut photo, generated people over real photographs."""

from __future__ import annotations

import pytest
import torch
from people import background, iou, place

from relightnet.checks import InputError
from relightnet.segment import LANDMARK_NAMES, segment_person


def test_astronaut_photo(astronaut, person_models):
    res = segment_person(astronaut, person_models)
    m = res.mask
    assert m.shape == (512, 512) and set(m.unique().tolist()) <= {0.0, 1.0}
    assert 0.3 < float(m.mean()) < 0.6
    for x, y in ((225, 120), (230, 60), (150, 400), (250, 330)):  # face, hair, suit (left), suit (chest)
        assert m[y, x] == 1, (x, y)
    for x, y in ((20, 100), (480, 20), (400, 200), (330, 60)):  # flag, wall, the model shuttle, wall
        assert m[y, x] == 0, (x, y)
    nose = res.landmarks[LANDMARK_NAMES.index("nose")]
    assert 190 < nose[0] < 260 and 100 < nose[1] < 170 and nose[3] > 0.9  # on her face, visible
    sh_l, sh_r = (res.landmarks[LANDMARK_NAMES.index(n)] for n in ("left_shoulder", "right_shoulder"))
    assert sh_l[0] > sh_r[0] and sh_l[1] > nose[1]  # she faces the camera: her left is the image's right
    assert res.world.shape == (33, 3) and res.score > 0.5


def test_generated_person_over_a_real_photo(person_scene, person_models):
    img, truth = person_scene
    res = segment_person(img, person_models)
    assert iou(res.mask, truth) > 0.9
    ankle = res.landmarks[LANDMARK_NAMES.index("left_ankle")]
    assert truth[int(ankle[1]) - 10:int(ankle[1]) + 10, int(ankle[0]) - 10:int(ankle[0]) + 10].any()


def test_person_cut_by_the_frame_edge(generated_people, person_models):
    """The crop leaves the image (its outside is black): the visible part is still found."""
    person, cover = generated_people[0]
    img, truth = place(background("rocket", (300, 400)), person, cover, height=0.9, cx=0.1, bottom=0.97)
    assert iou(segment_person(img, person_models).mask, truth) > 0.85


def test_the_largest_of_two_people_is_taken(generated_people, person_models):
    (a, ca), (b, cb) = generated_people
    img, small = place(background("coffee", (360, 640)), a, ca, height=0.45, cx=0.2, bottom=0.9)
    img, large = place(img, b, cb, height=0.85, cx=0.7, bottom=0.95)
    m = segment_person(img, person_models).mask
    assert iou(m, large) > 0.85 and float((m * small).sum()) < 0.05 * float(small.sum())


def test_no_person_is_a_one_line_error_naming_the_image(person_models):
    cat = background("chelsea", (300, 400))
    with pytest.raises(InputError, match=r"^cat\.jpg: no person found"):
        segment_person(cat, person_models, name="cat.jpg")
    with pytest.raises(InputError, match="expected float sRGB"):
        segment_person((cat * 255).to(torch.uint8), person_models)
