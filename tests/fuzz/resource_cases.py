"""Small hostile files that ask for huge resources (SECURITY.md's table and variants).

Each case writes its file(s) into a fresh folder and returns the ``relightnet`` command line
that reads them; :func:`resource_runner.run_capped` runs it in a capped child process.
``tests/fuzz/test_fuzz_resources.py`` asserts on the result; ``benchmarks/bench_untrusted.py
--resources`` prints the table.
Nothing here is committed as a file: every input is generated.
"""

from __future__ import annotations

import io
import json
import os
import struct
import sys
import zipfile
import zlib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import resource_fit  # noqa: E402
import resource_media  # noqa: E402
import resource_phone  # noqa: E402
import resource_phone_video  # noqa: E402
from resource_media import _png_chunk, png, video  # noqa: E402
from resource_runner import AS_CAP, RSS_BUDGET, THIRD_PARTY_TMP, WALL_CAP, Case, Result, run_capped  # noqa: E402

sys.path.pop(0)
__all__ = ["AS_CAP", "RSS_BUDGET", "THIRD_PARTY_TMP", "WALL_CAP", "Case", "Result", "run_capped", "CASES", "SLOW",
           "png", "onnx_bytes", "describe"]

# ---- the files ------------------------------------------------------------------------------

def zeros_deflated(nbytes: int) -> bytes:
    """A zlib stream of ``nbytes`` zero bytes (about nbytes / 1000 on disk)."""
    z, block, parts = zlib.compressobj(9), bytes(1 << 22), []
    for _ in range(nbytes >> 22):
        parts.append(z.compress(block))
    return b"".join(parts) + z.flush()


def _photo(folder: Path) -> list[str]:
    """A small photo and its all-person mask; the arguments that pass them to relight-image."""
    (folder / "photo.png").write_bytes(png(64))
    (folder / "mask.png").write_bytes(png(64, value=255))
    return ["photo.png", "--mask", "mask.png"]


def yaml_laughs(folder: Path) -> Case:
    """A jobs file whose ``command`` is 9⁸ strings through 8 levels of anchors and aliases (under 1 KB)."""
    lines = ['l0: &l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    lines += [f"l{i}: &l{i} [{', '.join([f'*l{i - 1}'] * 9)}]" for i in range(1, 9)]
    lines += ["jobs:", "  - command: *l8", "    args: [--out, x.png]"]
    (folder / "jobs.yaml").write_text("\n".join(lines) + "\n")
    return Case(["batch", "jobs.yaml"], "jobs.yaml")


def yaml_deep(folder: Path) -> Case:
    (folder / "jobs.yaml").write_text("jobs: " + "[" * 50_000 + "]" * 50_000 + "\n")
    return Case(["batch", "jobs.yaml"], "jobs.yaml")


def json_deep(folder: Path) -> Case:
    (folder / "jobs.json").write_text('{"jobs": ' + "[" * 50_000 + "]" * 50_000 + "}")
    return Case(["batch", "jobs.json"], "jobs.json")


def json_huge_number(folder: Path) -> Case:
    """A light .json whose coefficients are numbers of a million digits."""
    big = "9" * 1_000_000
    (folder / "light.json").write_text('{"sh": [' + ", ".join([f"[{big}, 1, 1]"] * 9) + "]}")
    return Case(["light", "convert", "light.json", "out.npz"], "light.json")


def jobs_many_empty(folder: Path) -> Case:
    """2,000 empty job entries: every one fails at once; the summary must not be rewritten 2,000 times."""
    (folder / "jobs.yaml").write_text("jobs:\n" + "  - {}\n" * 2000)
    return Case(["batch", "jobs.yaml"], "jobs.yaml", expect="failed-jobs",
                outputs=("jobs.summary.json",))


def synth_config_laughs(folder: Path) -> Case:
    lines = ['l0: &l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    lines += [f"l{i}: &l{i} [{', '.join([f'*l{i - 1}'] * 9)}]" for i in range(1, 9)]
    (folder / "config.yaml").write_text("\n".join(lines) + "\nseed: *l8\n")
    return Case(["synth", "--config", "config.yaml", "--out", "data"], "config.yaml")


def light_npz_inflated(folder: Path) -> Case:
    """A light ``.npz`` whose ``sh`` member inflates to 1 GiB (about 1 MB on disk)."""
    n = 1 << 30
    header = io.BytesIO()
    import numpy as np

    np.lib.format.write_array_header_1_0(header, {"descr": "<f4", "fortran_order": False,
                                                  "shape": (n // 36, 3, 3)})
    with zipfile.ZipFile(folder / "light.npz", "w", zipfile.ZIP_DEFLATED) as z, \
            z.open("sh.npy", "w", force_zip64=True) as f:
        f.write(header.getvalue())
        block = bytes(1 << 22)
        for _ in range((n // 36 * 36) >> 22):
            f.write(block)
    return Case(["light", "convert", "light.npz", "out.json"], "light.npz")


def png_ztxt(folder: Path) -> Case:
    """A 256² PNG with three zTXt chunks of 256 MiB each once inflated (under 1 MB on disk)."""
    text = _png_chunk(b"zTXt", b"Comment\x00\x00" + zeros_deflated(256 << 20))
    (folder / "photo.png").write_bytes(png(256, extra=text * 3))
    (folder / "mask.png").write_bytes(png(256, value=255))
    return Case(["relight-image", "photo.png", "--mask", "mask.png", "--light", "studio", "--out", "out.png"],
                "photo.png")


def _torch_save(obj, path: Path) -> None:
    import torch

    torch.save(obj, path)


def _shipped_state() -> dict:
    import torch

    from relightnet.model.checkpoint import SHIPPED

    return torch.load(SHIPPED, weights_only=True)


def checkpoint_laughs(folder: Path) -> Case:
    """A checkpoint whose ``net_config`` value is 9⁹ references to one list (pickle memo)."""
    state = _shipped_state()
    v: list = ["lol"] * 9
    for _ in range(9):
        v = [v] * 9
    state["net_config"] = {**state["net_config"], "width": v}
    _torch_save(state, folder / "bad.pt")
    argv = ["relight-image", *_photo(folder), "--light", "studio", "--checkpoint", "bad.pt", "--out", "out.png"]
    return Case(argv, "bad.pt")


def checkpoint_stride0(folder: Path) -> Case:
    """The shipped network's weights, each one value expanded by stride 0 (a few KB on disk)."""
    state = _shipped_state()
    state["model"] = {k: v.reshape(-1)[:1].clone().expand(v.shape) if v.numel() > 1 else v
                      for k, v in state["model"].items()}
    _torch_save(state, folder / "bad.pt")
    argv = ["relight-image", *_photo(folder), "--light", "studio", "--checkpoint", "bad.pt", "--out", "out.png"]
    return Case(argv, "bad.pt")


def checkpoint_wide(folder: Path) -> Case:
    """A width-2048 network's configuration with stride-0 weights: the architecture alone is too big."""
    import torch

    from relightnet.model.network import NetConfig, RelightNet

    state = _shipped_state()
    cfg = {**state["net_config"], "width": 2048, "max_width": 4096}
    with torch.device("meta"):
        shapes = {k: v.shape for k, v in RelightNet(NetConfig(**cfg)).state_dict().items()}
    state["net_config"], state["model"] = cfg, {k: torch.zeros(1).expand(s) for k, s in shapes.items()}
    _torch_save(state, folder / "bad.pt")
    argv = ["relight-image", *_photo(folder), "--light", "studio", "--checkpoint", "bad.pt", "--out", "out.png"]
    return Case(argv, "bad.pt")


def mp4_lying_stts(folder: Path) -> Case:
    """An 8-frame mp4 whose ``stts`` claims 20 M frames (2 KB): the avatar is rendered for its 8 real frames."""
    video(folder / "target.mp4", 8)
    data = bytearray((folder / "target.mp4").read_bytes())
    at = data.find(b"stts")
    data[at + 12:at + 16] = struct.pack(">I", 20_000_000)
    (folder / "target.mp4").write_bytes(bytes(data))
    argv = ["avatar", "--target", "target.mp4", "--light", "studio", "--no-occlusion", "--n-dirs", "16",
            "--out", "out.mp4"]
    return Case(argv, "target.mp4", expect="ok", outputs=("out.mp4", "out.lights.npz", "out.lights.png"))


def exr_8000(folder: Path) -> Case:
    """An EXR environment map whose data and display windows say 8000² (a 16² file, patched)."""
    import numpy as np
    import torch

    from relightnet.io import write_envmap

    write_envmap(folder / "env.exr", torch.from_numpy(np.full((16, 16, 3), 0.5, np.float32)))
    data = bytearray((folder / "env.exr").read_bytes())
    for name in (b"dataWindow", b"displayWindow"):
        at = data.find(name + b"\0box2i\0") + len(name) + 7 + 4
        data[at:at + 16] = struct.pack("<iiii", 0, 0, 7999, 7999)
    (folder / "env.exr").write_bytes(bytes(data))
    return Case(["light", "convert", "env.exr", "out.npz"], "env.exr")


def exr_at_limit(folder: Path) -> Case:
    """A 5000 × 2500 environment map (12.5 MP, at the default limit) projected to SH within the budget."""
    import numpy as np
    import torch

    from relightnet.io import write_envmap

    y, x = np.mgrid[0:2500, 0:5000].astype(np.float32)
    env = np.stack([x / 5000, y / 2500, np.full_like(x, 0.5)], -1)
    write_envmap(folder / "env.exr", torch.from_numpy(env))
    return Case(["light", "convert", "env.exr", "out.npz"], "env.exr", expect="ok", outputs=("out.npz",))


def stl_in_zip(folder: Path) -> Case:
    """A zip (0.5 MB) holding a binary STL with 10 M faces (477 MiB uncompressed)."""
    n = 10_000_000
    with zipfile.ZipFile(folder / "mesh.zip", "w", zipfile.ZIP_DEFLATED) as z, \
            z.open("mesh.stl", "w", force_zip64=True) as f:
        f.write(bytes(80) + struct.pack("<I", n))
        block = bytes(50 * 100_000)
        for _ in range(n // 100_000):
            f.write(block)
    return Case(["render", "mesh.zip", "--light", "studio", "--out", "out.png"], "mesh.zip")


def nested_zip(folder: Path) -> Case:
    """A zip holding a zip holding a mesh."""
    inner = io.BytesIO()
    with zipfile.ZipFile(inner, "w") as z:
        z.writestr("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with zipfile.ZipFile(folder / "mesh.zip", "w") as z:
        z.writestr("inner.zip", inner.getvalue())
    return Case(["render", "mesh.zip", "--light", "studio", "--out", "out.png"], "mesh.zip")


def stl_lying_header(folder: Path) -> Case:
    """A binary STL whose header claims 2³² − 1 faces (84 bytes)."""
    (folder / "mesh.stl").write_bytes(bytes(80) + struct.pack("<I", 2**32 - 1))
    return Case(["render", "mesh.stl", "--light", "studio", "--out", "out.png"], "mesh.stl")


def obj_fifo_mtllib(folder: Path) -> Case:
    """An OBJ whose ``mtllib`` is a FIFO beside it: the FIFO is never opened, the mesh renders."""
    (folder / "tri.obj").write_text("mtllib pipe.mtl\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n")
    os.mkfifo(folder / "pipe.mtl")
    return Case(["render", "tri.obj", "--light", "studio", "--res", "64", "--n-dirs", "16", "--out", "out.png"],
                "tri.obj", expect="ok", outputs=("out.png", "pipe.mtl"))


def gltf_fifo_buffer(folder: Path) -> Case:
    """A glTF whose buffer ``uri`` is a FIFO beside it."""
    doc = {"asset": {"version": "2.0"}, "buffers": [{"uri": "pipe.bin", "byteLength": 36}],
           "bufferViews": [{"buffer": 0, "byteLength": 36}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "nodes": [{"mesh": 0}],
           "scenes": [{"nodes": [0]}]}
    (folder / "mesh.gltf").write_text(json.dumps(doc))
    os.mkfifo(folder / "pipe.bin")
    return Case(["render", "mesh.gltf", "--light", "studio", "--out", "out.png"], "mesh.gltf",
                outputs=("pipe.bin",))


def onnx_bytes(side: int = 30000) -> bytes:
    """A graph with relightnet's inputs and outputs whose albedo multiplies by the sum of a
    ConstantOfShape of side² (a few hundred bytes; ONNX Runtime would fold it when making the session)."""
    import numpy as np
    from onnx import TensorProto, helper, numpy_helper

    f, b = TensorProto.FLOAT, TensorProto.BOOL
    inputs = [helper.make_tensor_value_info("image", f, ["batch", 3, "h", "w"]),
              helper.make_tensor_value_info("mask", f, ["batch", 1, "h", "w"]),
              helper.make_tensor_value_info("light_state", f, ["batch", 1, 9, 3]),
              helper.make_tensor_value_info("is_first", b, ["batch"])]
    outputs = [helper.make_tensor_value_info(n, f, None) for n in
               ("albedo", "transport", "light_raw", "light_smoothed", "light_state_out")]
    nodes = [
        helper.make_node("Constant", [], ["shape"], value=numpy_helper.from_array(np.array([side, side], np.int64))),
        helper.make_node("ConstantOfShape", ["shape"], ["big"],
                         value=numpy_helper.from_array(np.array([1.0], np.float32))),
        helper.make_node("ReduceSum", ["big"], ["total"], keepdims=0),
        helper.make_node("Mul", ["image", "total"], ["albedo"]),
        helper.make_node("Concat", ["image", "image", "image"], ["transport"], axis=1),
        helper.make_node("Constant", [], ["one"], value=numpy_helper.from_array(np.array([1], np.int64))),
        helper.make_node("Squeeze", ["light_state", "one"], ["light_raw"]),
        helper.make_node("Identity", ["light_raw"], ["light_smoothed"]),
        helper.make_node("Identity", ["light_state"], ["light_state_out"]),
    ]
    graph = helper.make_graph(nodes, "bomb", inputs, outputs)
    return helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)]).SerializeToString()


def onnx_constant_of_shape(folder: Path) -> Case:
    """An ONNX graph (under 1 KB) with relightnet's inputs and outputs and a ConstantOfShape of 30000²."""
    (folder / "model.onnx").write_bytes(onnx_bytes(30000))
    video(folder / "v.mp4", 2, 32)
    return Case(["onnx-run", "model.onnx", "--video", "v.mp4", "--out-dir", "out"], "model.onnx")


def onnx_wrong_outputs(folder: Path) -> Case:
    """An ONNX graph with relightnet's input names only (its one output is a ConstantOfShape of 300000²)."""
    import onnx

    proto = onnx.load_from_string(onnx_bytes(300000))
    del proto.graph.output[1:]
    (folder / "model.onnx").write_bytes(proto.SerializeToString())
    video(folder / "v.mp4", 2, 32)
    return Case(["onnx-run", "model.onnx", "--video", "v.mp4", "--out-dir", "out"], "model.onnx")


CASES = {
    "onnx-constant-of-shape-30000": onnx_constant_of_shape,
    "onnx-other-outputs": onnx_wrong_outputs,
    "exr-8000x8000": exr_8000,
    "exr-12.5MP-projected": exr_at_limit,
    "zip-stl-10M-faces": stl_in_zip,
    "zip-in-zip": nested_zip,
    "stl-header-4G-faces": stl_lying_header,
    "obj-mtllib-fifo": obj_fifo_mtllib,
    "gltf-buffer-fifo": gltf_fifo_buffer,
    "mp4-stts-20M-frames": mp4_lying_stts,
    "yaml-laughs": yaml_laughs,
    "yaml-deep": yaml_deep,
    "json-deep": json_deep,
    "json-huge-number": json_huge_number,
    "jobs-2000-empty": jobs_many_empty,
    "synth-config-laughs": synth_config_laughs,
    "light-npz-1GiB": light_npz_inflated,
    "png-ztxt-3x256MiB": png_ztxt,
    "checkpoint-laughs": checkpoint_laughs,
    "checkpoint-stride0": checkpoint_stride0,
    "checkpoint-wide": checkpoint_wide,
    **resource_media.CASES,
    **resource_fit.CASES,
    **resource_phone.CASES,
    **resource_phone_video.CASES,
}
#: Cases that take more than a few seconds (marked ``slow`` in the test).
SLOW = {*resource_media.SLOW, *resource_fit.SLOW, *resource_phone.SLOW, *resource_phone_video.SLOW,
        "exr-12.5MP-projected", "mp4-stts-20M-frames"}


def describe(name: str) -> str:
    """The first line of a case's docstring (for the benchmark's table)."""
    doc = CASES[name].__doc__ or name
    return doc.strip().splitlines()[0]


if __name__ == "__main__":  # python tests/fuzz/resource_cases.py NAME FOLDER: run one case, print the result
    folder = Path(sys.argv[2])
    folder.mkdir(parents=True, exist_ok=True)
    case = CASES[sys.argv[1]](folder)
    res = run_capped(case, folder)
    print(json.dumps({"rc": res.rc, "rss_mb": res.rss >> 20, "wall": round(res.wall, 2), "left": res.leftovers,
                      "stderr": res.stderr[-600:]}))
