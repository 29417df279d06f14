"""y-up world ⇄ Blender z-up: algebra here, and Blender's equirectangular convention measured with Cycles."""

import numpy as np
import pytest
import torch

from relightnet.blender import blender_to_world, world_to_blender
from relightnet.blender.frames import BLENDER_FROM_WORLD, equirect_directions, latlong_to_equirect, transform_to_blender
from relightnet.io import write_envmap
from relightnet.sh import directions_to_latlong, latlong_directions


def test_map_is_a_proper_rotation_keeping_up_and_front():
    C = BLENDER_FROM_WORLD
    assert torch.allclose(C @ C.T, torch.eye(3, dtype=C.dtype)) and torch.det(C) == 1
    v = torch.randn(5, 3, dtype=torch.float64)
    assert torch.allclose(world_to_blender(v), v @ C.T)
    assert torch.allclose(blender_to_world(world_to_blender(v)), v)
    # world up (+y) is Blender up (+z); the person faces world +z = Blender's front (-y).
    assert world_to_blender(torch.tensor([0.0, 1.0, 0.0])).tolist() == [0.0, 0.0, 1.0]
    assert world_to_blender(torch.tensor([0.0, 0.0, 1.0])).tolist() == [0.0, -1.0, 0.0]


def test_transform_to_blender_maps_points_like_world_to_blender():
    m = torch.eye(4, dtype=torch.float64)
    m[:3, 3] = torch.tensor([0.3, 1.2, -2.0])
    p_local = torch.tensor([0.1, 0.2, 0.3, 1.0], dtype=torch.float64)
    p_b = transform_to_blender(m) @ p_local
    assert torch.allclose(p_b[:3], world_to_blender((m @ p_local)[:3]))


def test_equirect_directions_are_our_latlong_rolled_a_quarter_turn():
    h, w = 16, 32
    ours, _ = latlong_directions(h, w, dtype=torch.float64)
    blender = equirect_directions(h, w, dtype=torch.float64)
    assert torch.allclose(blender, latlong_to_equirect(ours), atol=1e-12)
    # The Blender image centre looks along world +x (= Blender +x); the top row is up.
    centre = equirect_directions(15, 36, dtype=torch.float64)[7, 17:19].mean(0)
    assert torch.allclose(centre / centre.norm(), torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64), atol=1e-12)
    assert (blender[0, :, 1] > 0.99).all()
    with pytest.raises(ValueError):
        latlong_to_equirect(torch.zeros(4, 6, 3))


def test_cycles_sees_the_texel_frames_predicts(tmp_path):
    """A camera looking along world ±x, ±z and up renders the world texel our mapping names."""
    from relightnet.blender._bpy import reset
    from relightnet.blender.cycles import configure_cycles, render_current

    h, w = 32, 64
    # Each texel stores its own (column, row) so the rendered background names the texel seen.
    cols, rows = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    code = np.stack([cols / w, rows / h, np.zeros_like(cols)], -1).astype(np.float32)
    write_envmap(tmp_path / "code.exr", code)
    bpy = reset()
    from mathutils import Matrix

    scene = bpy.context.scene
    configure_cycles(scene, spp=1, bounces=0, filter_width=0.01, denoise=False)
    scene.render.film_transparent = False
    scene.render.resolution_x = scene.render.resolution_y = 5
    world = bpy.data.worlds.new("w")
    scene.world = world
    env = world.node_tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(str(tmp_path / "code.exr"))
    env.image.colorspace_settings.name = "Linear Rec.709"
    env.interpolation = "Closest"
    world.node_tree.links.new(env.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    for d in ([1.0, 0, 0], [-1.0, 0, 0], [0, 0, 1.0], [0, 0, -1.0], [0.05, 1.0, 0.0]):
        d = torch.tensor(d, dtype=torch.float64)
        d = d / d.norm()
        up = torch.tensor([0.0, 1.0, 0.0] if abs(d[1]) < 0.9 else [1.0, 0.0, 0.0], dtype=torch.float64)
        x = torch.linalg.cross(up, -d)
        x = x / x.norm()
        m = torch.eye(4, dtype=torch.float64)
        m[:3, 0], m[:3, 1], m[:3, 2] = x, torch.linalg.cross(-d, x), -d  # camera looks along its -z
        cam.matrix_world = Matrix(transform_to_blender(m).tolist())
        px, _ = render_current(tmp_path / "bg.exr")
        u, v = float(px[2, 2, 0]) * w, float(px[2, 2, 1]) * h  # texel centre seen at the image centre
        uo, vo = directions_to_latlong(d, h, w).tolist()  # our texel of d; Blender's is W/4 to the left
        du = (u - (uo - w / 4) + w / 2) % w - w / 2
        assert abs(du) <= 1.0 and abs(v - vo) <= 1.0, (d.tolist(), u, v, uo, vo)
