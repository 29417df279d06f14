"""How much geometry a .blend asks Blender to build, counted before Blender builds it.

A small .blend can ask for a huge mesh: a cube with a subdivision surface of render level 11
is 25 M faces, an array modifier of a million copies or a particle system instancing a mesh
a million times likewise; Cycles holds ~100–200 bytes per triangle, so such a file takes
gigabytes long before the first sample — Blender builds it as soon as it opens the file.
:func:`blend_face_count` counts the faces each object will have from its own data and its
render-visible modifiers, before the file is opened and without evaluating anything:

- a mesh: its polygons; each subdivision-surface or multires modifier multiplies them by
  4^(render levels); an array modifier of a fixed count by the count; a screw modifier by its
  render steps × iterations; other modifiers keep the count (deforming, cutting or joining
  ones never multiply it by more than a small factor);
- a particle system rendered as an object or a collection adds (particles + rendered children)
  × the instanced faces;
- a collection instance (an empty instancing a collection) adds that collection's faces.

What cannot be counted ahead is refused: a geometry-nodes modifier, an array modifier fitted
to a length or a curve, and Cycles' adaptive subdivision (a subdivision modifier's switch).
"""

from __future__ import annotations

from ..checks import InputError

__all__ = ["MAX_SCENE_FACES", "blend_face_count", "check_blend_geometry"]

#: The most faces a .blend's scene may ask for (about 1.5 GB of Cycles' geometry at ~150 bytes a
#: triangle, two triangles a quad, within the 2 GB command budget with Blender itself).
MAX_SCENE_FACES = 5_000_000


def _modifier_factor(path, ob, m) -> int:
    if m.type in ("SUBSURF", "MULTIRES"):
        if getattr(m, "use_adaptive_subdivision", False):
            raise InputError(f"{path}: object {ob.name!r}: adaptive subdivision (diced by the camera: its faces "
                             "cannot be bounded before Blender builds them)")
        return 4 ** int(m.render_levels)
    if m.type == "ARRAY":
        if m.fit_type != "FIXED_COUNT":
            raise InputError(f"{path}: object {ob.name!r}: an array modifier fitted to a length or a curve "
                             "(its count cannot be bounded before Blender builds it)")
        return max(1, int(m.count))
    if m.type == "SCREW":
        return max(1, int(m.render_steps)) * max(1, int(m.iterations))
    if m.type == "NODES":
        raise InputError(f"{path}: object {ob.name!r}: a geometry-nodes modifier (its output cannot be bounded "
                         "before Blender builds it)")
    return 1


def _object_faces(path, ob, depth: int = 0) -> int:
    if depth > 8:
        raise InputError(f"{path}: instances nested more than 8 deep (object {ob.name!r})")
    n = 0
    if ob.type == "MESH":
        n = len(ob.data.polygons)
        for m in ob.modifiers:
            if m.show_render:
                n *= _modifier_factor(path, ob, m)
        for ps in getattr(ob, "particle_systems", ()):
            s = ps.settings
            if s.render_type == "OBJECT" and s.instance_object is not None:
                each = _object_faces(path, s.instance_object, depth + 1)
            elif s.render_type == "COLLECTION" and s.instance_collection is not None:
                each = _collection_faces(path, s.instance_collection, depth + 1)
            else:
                continue
            n += (int(s.count) + int(s.count) * int(getattr(s, "rendered_child_count", 0))) * each
    if ob.instance_type == "COLLECTION" and ob.instance_collection is not None:
        n += _collection_faces(path, ob.instance_collection, depth + 1)
    return n


def _collection_faces(path, coll, depth: int) -> int:
    return sum(_object_faces(path, ob, depth) for ob in coll.all_objects)


def blend_face_count(path) -> int:
    """Faces the render-visible objects of a .blend file will have (module docstring), read without
    opening it as the current file: Blender builds every modifier of a scene it opens, so the
    objects are appended into the session, outside any scene (nothing is evaluated, no script or
    driver runs), and counted; opening the file afterwards replaces them. Every object of the file
    counts, in a scene or not (an over-estimate is safe).

    Raises:
        InputError: geometry that cannot be counted ahead, or a file Blender cannot read (named).
    """
    from ._bpy import reset

    bpy = reset()  # an empty session: Blender cannot append from the file it has open
    try:
        with bpy.data.libraries.load(str(path), link=False) as (src, dst):
            dst.objects = list(src.objects)
    except (OSError, RuntimeError) as e:
        msg = str(e).strip().splitlines()[-1] if str(e).strip() else "unreadable"
        raise InputError(f"{path}: cannot open with Blender ({msg})") from None
    return sum(_object_faces(path, ob) for ob in dst.objects if ob is not None and not ob.hide_render)


def check_blend_geometry(path) -> int:
    """Refuse a .blend whose objects ask for more than :data:`MAX_SCENE_FACES` faces before Blender
    builds anything (:func:`blend_face_count`); returns the count.

    Raises:
        InputError: one line naming the file and what it asks for.
    """
    n = blend_face_count(path)
    if n > MAX_SCENE_FACES:
        raise InputError(f"{path}: its objects and modifiers ask for {n:,} faces; at most {MAX_SCENE_FACES:,} are "
                         "rendered")
    return n
