"""Faces a .blend asks for, counted from its meshes and modifiers before Blender builds them."""

import pytest

from relightnet.checks import InputError

pytestmark = pytest.mark.blender


def _cube(bpy, name="cube"):
    ob = bpy.data.objects.new(name, bpy.data.meshes.new(name))
    ob.data.from_pydata([(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], [],
                        [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)])
    bpy.context.scene.collection.objects.link(ob)
    return ob


def _save(bpy, path):
    bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)
    return path


def _cube_file(path, render_levels=2, count=3, fit_type="FIXED_COUNT", adaptive=False, evaluated=None):
    """A cube with a subdivision surface, an array and a hidden subdivision, saved to ``path``; with
    ``evaluated`` (a list), Blender's own face count of the evaluated cube is appended to it."""
    from relightnet.blender._bpy import reset

    bpy = reset()
    cube = _cube(bpy)
    sub = cube.modifiers.new("s", "SUBSURF")
    sub.levels, sub.render_levels, sub.use_adaptive_subdivision = 2, render_levels, adaptive
    arr = cube.modifiers.new("a", "ARRAY")
    arr.count, arr.fit_type = count, fit_type
    hidden = cube.modifiers.new("h", "SUBSURF")
    hidden.render_levels, hidden.show_render, hidden.show_viewport = 6, False, False  # not rendered: not counted
    if evaluated is not None:
        evaluated.append(len(cube.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.polygons))
    return _save(bpy, path)


def test_modifiers_multiply_as_blender_builds_them(tmp_path):
    from relightnet.blender.geometry import blend_face_count, check_blend_geometry

    built = []
    f = _cube_file(tmp_path / "f.blend", evaluated=built)
    assert built == [6 * 4**2 * 3] and blend_face_count(f) == 6 * 4**2 * 3 == check_blend_geometry(f)
    with pytest.raises(InputError, match=r"g\.blend: its objects and modifiers ask for 75,497,472 faces"):
        check_blend_geometry(_cube_file(tmp_path / "g.blend", render_levels=11))  # 6 · 4¹¹ · 3
    with pytest.raises(InputError, match="array modifier fitted to a length"):
        check_blend_geometry(_cube_file(tmp_path / "h.blend", fit_type="FIT_LENGTH"))
    with pytest.raises(InputError, match="adaptive subdivision"):  # diced by the camera at render time
        check_blend_geometry(_cube_file(tmp_path / "i.blend", adaptive=True))


def test_collection_instances_count(tmp_path):
    from relightnet.blender._bpy import reset
    from relightnet.blender.geometry import blend_face_count

    bpy = reset()
    coll = bpy.data.collections.new("c")
    tri = bpy.data.objects.new("tri", bpy.data.meshes.new("tri"))
    tri.data.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
    coll.objects.link(tri)
    for i in range(4):  # four empties instancing the one-triangle collection
        e = bpy.data.objects.new(f"e{i}", None)
        e.instance_type, e.instance_collection = "COLLECTION", coll
        bpy.context.scene.collection.objects.link(e)
    # the four instances, and the triangle itself (every object of the file counts: an over-estimate)
    assert blend_face_count(_save(bpy, tmp_path / "f.blend")) == 4 + 1
