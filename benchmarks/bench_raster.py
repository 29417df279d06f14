"""Rasterize + interpolate 9 channels on the Anny body mesh vs moderngl (EGL, Mesa llvmpipe).

Both sides render the same mesh (Anny default body: 13,718 vertices, 27,420 triangles,
converted to y-up, feet at y = 0) with the same camera (``default_camera``: 35° FOV,
3 m) and 9 float channels per vertex, in one process, alternating runs; medians.

- relightnet: ``rasterize(camera.transform(verts), faces, size)`` then
  ``interpolate(attr (V, 9), frags, faces)`` → a (1, H, W, 9) tensor.
- moderngl: per frame, upload the vertex buffer, draw into three RGBA32F colour
  attachments + a depth buffer, read the three attachments back to numpy.

Usage::

    ANNY_CACHE_DIR=.cache/anny python benchmarks/bench_raster.py [--sizes 256 512 1024] [--runs 20]
        [--threads 2] [--no-compile]

The eager column is the default ``rasterize``; the compiled column passes ``compile=True``
(its one-off compilation time is printed separately and not in the medians).

moderngl needs ``pip install moderngl`` and the Debian packages ``libegl1 libegl-mesa0
libgl1-mesa-dri libgles2``; without it the peer column reads n/a.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
import warnings

import numpy as np
import torch

from relightnet.raster import default_camera, interpolate, rasterize


def load_anny_mesh() -> tuple[torch.Tensor, torch.Tensor, str]:
    """Anny's default posed body as (V, 3) y-up vertices (feet at y = 0) and (F, 3) faces."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            import anny

            model = anny.Anny()
            with torch.no_grad():
                v = model()["vertices"][0].float()
            faces = model.get_triangular_faces().long()
        v = torch.stack([v[:, 0], v[:, 2], -v[:, 1]], dim=1)  # z-up, facing -y → y-up, facing +z
        v[:, 1] -= v[:, 1].min()
        return v, faces, "Anny default body"
    except Exception as exc:  # anny missing or its cache unbuilt: a mesh of similar size
        import trimesh

        m = trimesh.creation.icosphere(subdivisions=6)
        m.apply_scale([0.25, 0.85, 0.15])
        m.apply_translation([0, 0.85, 0])
        return (torch.tensor(m.vertices, dtype=torch.float32), torch.tensor(m.faces, dtype=torch.long),
                f"ellipsoid ({type(exc).__name__}: anny unavailable)")


class ModernGLPeer:
    """The same frame with moderngl on EGL (surfaceless, Mesa llvmpipe on CPU)."""

    VS = """
        #version 330
        uniform mat4 mvp;
        in vec3 in_pos; in vec3 in_a; in vec3 in_b; in vec3 in_c;
        out vec3 a; out vec3 b; out vec3 c;
        void main() { gl_Position = mvp * vec4(in_pos, 1.0); a = in_a; b = in_b; c = in_c; }
    """
    FS = """
        #version 330
        in vec3 a; in vec3 b; in vec3 c;
        layout(location = 0) out vec4 o0; layout(location = 1) out vec4 o1; layout(location = 2) out vec4 o2;
        void main() { o0 = vec4(a, 1.0); o1 = vec4(b, 1.0); o2 = vec4(c, 1.0); }
    """

    def __init__(self, verts: np.ndarray, faces: np.ndarray, attr: np.ndarray, mvp: np.ndarray) -> None:
        os.environ.setdefault("EGL_PLATFORM", "surfaceless")
        import moderngl

        self.moderngl = moderngl
        self.ctx = moderngl.create_standalone_context(backend="egl")
        self.renderer = self.ctx.info.get("GL_RENDERER", "?")
        self.prog = self.ctx.program(vertex_shader=self.VS, fragment_shader=self.FS)
        self.prog["mvp"].write(mvp.T.astype("f4").tobytes())  # column-major
        self.data = np.concatenate([verts, attr], axis=1).astype("f4")
        self.vbo = self.ctx.buffer(self.data.tobytes())
        self.ibo = self.ctx.buffer(faces.astype("i4").tobytes())
        self.vao = self.ctx.vertex_array(self.prog, [(self.vbo, "3f 3f 3f 3f", "in_pos", "in_a", "in_b", "in_c")],
                                         index_buffer=self.ibo)
        self.fbos = {}

    def render(self, size: tuple[int, int]) -> list[np.ndarray]:
        H, W = size
        if size not in self.fbos:
            att = [self.ctx.texture((W, H), 4, dtype="f4") for _ in range(3)]
            self.fbos[size] = self.ctx.framebuffer(att, self.ctx.depth_renderbuffer((W, H)))
        fbo = self.fbos[size]
        fbo.use()
        self.ctx.enable(self.moderngl.DEPTH_TEST)
        fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        self.vbo.write(self.data.tobytes())  # a new pose every frame
        self.vao.render(self.moderngl.TRIANGLES)
        return [np.frombuffer(fbo.read(components=4, attachment=i, dtype="f4"), dtype="f4").reshape(H, W, 4)
                for i in range(3)]


def median_ms(times: list[float]) -> float:
    return 1e3 * statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[256, 512, 1024])
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--compile", action=argparse.BooleanOptionalAction, default=True,
                    help="also time rasterize(..., compile=True) (torch.compile; needs a C++ compiler)")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)

    verts, faces, name = load_anny_mesh()
    g = torch.Generator().manual_seed(0)
    attr = torch.rand(verts.shape[0], 9, generator=g)
    try:
        import moderngl

        mvp = default_camera(size=(512, 512)).full[0].numpy()
        peer = ModernGLPeer(verts.numpy(), faces.numpy(), attr.numpy(), mvp)
        peer_name = f"moderngl {moderngl.__version__} ({peer.renderer})"
    except Exception as exc:
        peer, peer_name = None, f"moderngl n/a ({type(exc).__name__}: {exc})"

    print(f"mesh: {name}, {verts.shape[0]} vertices, {faces.shape[0]} triangles; 9 channels; "
          f"torch {torch.__version__}, {args.threads} threads; peer: {peer_name}\n")
    compile_s = None
    if args.compile:
        t = time.perf_counter()
        cam = default_camera(size=(args.sizes[0],) * 2)
        rasterize(cam.transform(verts), faces, (args.sizes[0],) * 2, compile=True)
        compile_s = time.perf_counter() - t
    print("| size | relightnet eager (ms) | relightnet compile=True (ms) | moderngl draw+readback (ms) "
          "| ratio eager/peer | ratio compiled/peer | covered px | mask agreement |")
    print("|---|---|---|---|---|---|---|---|")
    for S in args.sizes:
        cam = default_camera(size=(S, S))

        def ours(compile=False, cam=cam, S=S):
            frags = rasterize(cam.transform(verts), faces, (S, S), compile=compile)
            return frags, interpolate(attr, frags, faces)

        frags, img = ours()
        agree = "n/a"
        if peer is not None:
            out = peer.render((S, S))
            peer_mask = torch.from_numpy(out[0][::-1, :, 3].copy() > 0)
            agree = f"{(peer_mask == frags.mask[0]).float().mean().item():.5f}"
        runs = {"eager": [], "compiled": [], "peer": []}
        calls = {"eager": ours, "compiled": lambda: ours(True), "peer": lambda S=S: peer.render((S, S))}
        active = ["eager"] + (["compiled"] if args.compile else []) + (["peer"] if peer is not None else [])
        for _ in range(3):
            for k in active:
                calls[k]()
        for _ in range(args.runs):  # alternate, so that load changes hit every column alike
            for k in active:
                t = time.perf_counter()
                calls[k]()
                runs[k].append(time.perf_counter() - t)
        med = {k: median_ms(v) if v else None for k, v in runs.items()}

        def fmt(x):
            return f"{x:.2f}" if x is not None else "n/a"

        def ratio(a, b):
            return f"{a / b:.2f}" if a is not None and b is not None else "n/a"

        print(f"| {S}² | {fmt(med['eager'])} | {fmt(med['compiled'])} | {fmt(med['peer'])} "
              f"| {ratio(med['eager'], med['peer'])} | {ratio(med['compiled'], med['peer'])} "
              f"| {frags.pix.numel()} | {agree} |")
    if compile_s is not None:
        print(f"\ncompile=True: first call (compilation) took {compile_s:.1f} s")


if __name__ == "__main__":
    main()
