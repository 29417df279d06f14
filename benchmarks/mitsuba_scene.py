"""Mitsuba 3 scenes that match relightnet's conventions, for the path-traced reference check.

Everything here converts one relightnet object into its Mitsuba counterpart and is
checked by ``bench_reference.py`` (see the ``check_*`` functions):

- **Environment map.** Mitsuba's ``envmap`` (3.9) stores texel (row i, column j) of an
  (H, W) bitmap at the local direction ``(sin φ sin θ, cos θ, −cos φ sin θ)`` with
  ``θ = π i / (H − 1)`` and ``φ = 2π (j + ½) / W`` (bilinear in between, column W wraps to
  column 0). That is relightnet's world frame with ``to_world`` = identity, but the
  column origin differs by π from ``relightnet.sh.directions`` (whose image centre looks
  along −z) and the rows sit on the poles instead of half a row inside them. So the
  bitmap is not a resampled ``sh_to_envmap`` image: the SH light is evaluated exactly at
  Mitsuba's own texel directions (:func:`envmap_bitmap`).
- **Camera.** A ``perspective`` sensor at the camera's eye, looking down its −z axis with
  its +y up (``look_at``), vertical field of view from the projection matrix, a ``box``
  pixel filter (a pixel averages its own square only; pixel (i, j) covers
  ``[j, j+1] × [i, i+1]`` as in relightnet) and an RGBA film whose alpha is coverage.
- **Mesh.** Positions, faces (counter-clockwise = front in both) and *our* vertex
  normals (Mitsuba interpolates them as shading normals, like our rasterizer
  interpolates per-vertex transport), a one-sided ``diffuse`` BSDF of reflectance ρ
  (a constant, or a per-vertex ``mesh_attribute``).

Scale: Mitsuba's diffuse BSDF is ρ/π, relightnet's pixel is ρ ⊙ ∫ V max(n·ω, 0) L dω
(no 1/π), so ``ours = π · mitsuba`` for the same ρ and light.
"""

from __future__ import annotations

import math
import os
import time

import numpy as np
import torch

from relightnet.raster import Camera
from relightnet.sh import radiance, world_to_light

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
Y00 = 0.5 / math.sqrt(math.pi)


def init_mitsuba(variant: str = "llvm_ad_rgb"):
    """Import Mitsuba on ``variant`` (Debian's LLVM 19 for the llvm variants) and return the module."""
    if os.path.exists(LLVM):
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM)
    import mitsuba as mi

    mi.set_variant(variant)
    return mi


def mitsuba_latlong_directions(h: int, w: int) -> np.ndarray:
    """(H, W, 3) float64 world directions of the texels of an (H, W) Mitsuba ``envmap`` bitmap."""
    theta = math.pi * np.arange(h) / (h - 1)
    phi = 2 * math.pi * (np.arange(w) + 0.5) / w
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    return np.stack([st * np.sin(phi)[None], np.broadcast_to(ct, (h, w)), -st * np.cos(phi)[None]], -1)


def sh_radiance_world(light: torch.Tensor, dirs_world: np.ndarray) -> np.ndarray:
    """(..., 3) radiance of an SH light (K, 3) (light frame) in world directions (..., 3)."""
    d = torch.as_tensor(dirs_world, dtype=torch.float64)
    return radiance(light.double(), world_to_light(d)).numpy()


def envmap_bitmap(light: torch.Tensor, h: int = 256) -> np.ndarray:
    """(H, 2H, 3) float32 bitmap for Mitsuba's ``envmap``: the SH light at Mitsuba's texel directions."""
    return np.ascontiguousarray(sh_radiance_world(light, mitsuba_latlong_directions(h, 2 * h)), dtype=np.float32)


def nonnegative_light(light: torch.Tensor, h: int = 1024) -> tuple[torch.Tensor, np.ndarray]:
    """Add the smallest per-channel constant radiance that makes an SH light non-negative.

    The minimum is taken on a dense lat-long grid (H × 2H, both poles included); a band-2
    function varies slowly, so this is its minimum over the sphere to ~1e-5 relative.

    Returns:
        (the modified (K, 3) light, the added radiance per channel (3,)).
    """
    env = sh_radiance_world(light, mitsuba_latlong_directions(h, 2 * h))
    dc = np.maximum(-env.reshape(-1, 3).min(0), 0.0)
    out = light.clone().double()
    out[0] += torch.as_tensor(dc) / Y00
    return out.to(light.dtype), dc


def envmap_emitter(mi, bitmap: np.ndarray):
    """A Mitsuba ``envmap`` emitter from an (H, W, 3) float32 bitmap (to_world = identity)."""
    return mi.load_dict({"type": "envmap", "bitmap": mi.Bitmap(np.ascontiguousarray(bitmap, np.float32))})


def diffuse_mesh(mi, verts, faces, normals, albedo, name: str = "mesh"):
    """A Mitsuba mesh with our positions, faces and vertex normals, and a diffuse BSDF.

    Args:
        verts: (V, 3). faces: (F, 3). normals: (V, 3) unit (kept: Mitsuba does not recompute them).
        albedo: a float, an RGB triple, or a (V, 3) per-vertex reflectance.
    """
    v = np.ascontiguousarray(np.asarray(verts, np.float32))
    f = np.ascontiguousarray(np.asarray(faces).astype(np.uint32))
    n = np.ascontiguousarray(np.asarray(normals, np.float32))
    mesh = mi.Mesh(name, len(v), len(f), has_vertex_normals=True)
    p = mi.traverse(mesh)
    p["vertex_positions"] = mi.Float(v.ravel())
    p["vertex_normals"] = mi.Float(n.ravel())
    p["faces"] = mi.UInt32(f.ravel())
    p.update()
    a = np.asarray(albedo, np.float32)
    if a.ndim == 2:
        mesh.add_attribute("vertex_color", 3, mi.Float(np.ascontiguousarray(a).ravel()))
        refl = {"type": "mesh_attribute", "name": "vertex_color"}
    else:
        refl = {"type": "rgb", "value": np.broadcast_to(a, (3,)).astype(float).tolist()}
    mesh.set_bsdf(mi.load_dict({"type": "diffuse", "reflectance": refl}))
    return mesh


def camera_params(camera: Camera) -> dict:
    """Eye, target, up, vertical FOV (degrees), (H, W) and near plane of a centred perspective Camera."""
    R = camera.R[0].double()
    eye = camera.position[0].double()
    P = camera.proj[0].double()
    H, W = camera.size
    if abs(P[0, 2]) > 1e-6 or abs(P[1, 2]) > 1e-6 or abs(P[0, 0] * W - P[1, 1] * H) > 1e-4 * float(P[1, 1] * H):
        raise ValueError("camera_params: only centred perspective cameras with square pixels are supported")
    a, b = float(P[2, 2]), float(P[2, 3])
    near = b / (a - 1)  # OpenGL: a = -(f+n)/(f-n), b = -2fn/(f-n)
    return dict(eye=eye.tolist(), target=(eye - R[2]).tolist(), up=R[1].tolist(),
                fov=math.degrees(2 * math.atan(1 / float(P[1, 1]))), size=(H, W), near=near)


def sensor_dict(mi, camera: Camera, spp: int, seed: int = 0) -> dict:
    """A ``perspective`` sensor matching ``camera`` (box filter, RGBA film, multi-jittered sampler)."""
    c = camera_params(camera)
    H, W = c["size"]
    return {
        "type": "perspective",
        "fov": c["fov"],
        "fov_axis": "y",
        "near_clip": c["near"],
        "far_clip": 1e4,
        "to_world": mi.ScalarTransform4f().look_at(origin=c["eye"], target=c["target"], up=c["up"]),
        "film": {"type": "hdrfilm", "width": W, "height": H, "pixel_format": "rgba",
                 "rfilter": {"type": "box"}},
        "sampler": {"type": "multijitter", "sample_count": int(spp), "seed": int(seed)},
    }


def build_scene(mi, meshes: list, bitmap: np.ndarray, camera: Camera, spp: int, max_depth: int):
    """A scene: the meshes, the env map, the matching sensor, a ``path`` integrator (emitters hidden)."""
    d = {"type": "scene",
         "integrator": {"type": "path", "max_depth": int(max_depth), "hide_emitters": True},
         "sensor": sensor_dict(mi, camera, spp),
         "env": envmap_emitter(mi, bitmap)}
    for i, m in enumerate(meshes):
        d[f"shape{i}"] = m
    return mi.load_dict(d)


def render(mi, scene, spp: int, seed: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Render once; returns (rgb (H, W, 3), alpha coverage (H, W), seconds)."""
    import drjit as dr

    t0 = time.perf_counter()
    img = mi.render(scene, spp=int(spp), seed=int(seed))
    dr.eval(img)
    out = np.asarray(img)
    sec = time.perf_counter() - t0
    return out[..., :3].astype(np.float64), out[..., 3].astype(np.float64), sec


def render_centres(mi, scene, spp: int, seed: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Render with every camera ray through its pixel *centre* (relightnet's rasterizer samples there).

    The scene's ``path`` integrator is called on one wavefront of H·W·spp rays, the
    ``spp`` rays of a pixel consecutive (as ``mi.render`` lays them out, so the
    multi-jittered sampler stratifies each pixel's light samples); results are
    scatter-added per pixel inside the same kernel.

    Returns:
        (rgb (H, W, 3) mean radiance, coverage (H, W) in {0, 1}, seconds).
    """
    import drjit as dr

    t0 = time.perf_counter()
    sensor, integ = scene.sensors()[0], scene.integrator()
    W, H = (int(x) for x in sensor.film().size())
    sampler = sensor.sampler().clone()
    sampler.set_sample_count(int(spp))
    spp = sampler.sample_count()  # the multi-jittered sampler may round it up (use squares: 256, 1024)
    n = H * W * spp
    sampler.set_samples_per_wavefront(spp)
    sampler.seed(int(seed), n)
    pix = dr.arange(mi.UInt32, n) // dr.opaque(mi.UInt32, spp)
    pos = mi.Point2f((mi.Float(pix % W) + 0.5) / W, (mi.Float(pix // W) + 0.5) / H)
    ray, _ = sensor.sample_ray(mi.Float(0.0), mi.Float(0.5), pos, mi.Point2f(0.5, 0.5))
    spec, valid, _ = integ.sample(scene, sampler, mi.RayDifferential3f(ray))
    acc = [dr.zeros(mi.Float, H * W) for _ in range(4)]
    for a, v in zip(acc, (spec[0], spec[1], spec[2], mi.Float(valid)), strict=True):
        dr.scatter_add(a, v, pix)
    dr.eval(*acc)
    out = np.stack([np.asarray(a) for a in acc], -1).reshape(H, W, 4) / spp
    sec = time.perf_counter() - t0
    return out[..., :3].astype(np.float64), out[..., 3].astype(np.float64), sec
