"""Fuzz corpus, media and model readers: images, masks, videos, HDR maps, checkpoints, ONNX models."""

from __future__ import annotations

import io
import random
import struct
import zlib
from pathlib import Path

import numpy as np

BIG_DIMS = ((12000, 12000), (65535, 65535), (1, 10**8), (10**8, 1), (0, 100), (100, 0), (9000, 8000),
            (2**31 - 1, 2), (4, 4))


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def png_header_only(w: int, h: int, idat: bytes = b"") -> bytes:
    """A PNG whose (valid-CRC) header says w × h, with little or no pixel data."""
    ihdr = struct.pack(">IIBBBBB", w & 0xFFFFFFFF, h & 0xFFFFFFFF, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr) + _chunk(b"IDAT", idat or zlib.compress(bytes(64))) \
        + _chunk(b"IEND", b"")


def image_seeds(tmp: Path) -> dict[str, bytes]:
    import av

    from relightnet.io import write_image
    from relightnet.io.image import _encode

    g = np.random.default_rng(3)
    img = g.integers(0, 255, (24, 16, 3), dtype=np.uint8)
    write_image(tmp / "seed.png", img, alpha=g.uniform(size=(24, 16)))
    frame = av.VideoFrame.from_ndarray(img, format="rgb24").reformat(format="yuvj420p")
    return {".png": (tmp / "seed.png").read_bytes(), ".jpg": _encode("mjpeg", frame)}


def image_cases(r: random.Random):
    w, h = r.choice(BIG_DIMS)
    kind = r.choice(["png", "jpeg", "gif", "bmp", "webp", "pnm", "tiff"])
    if kind == "png":
        yield "png-dims", png_header_only(w, h)
    elif kind == "jpeg":  # SOF0 with the dimensions, then junk
        sof = b"\xff\xc0" + struct.pack(">HBHHB", 11, 8, h & 0xFFFF, w & 0xFFFF, 1) + b"\x01\x11\x00"
        yield "jpeg-dims", b"\xff\xd8" + b"\xff\xe0\x00\x10JFIF\x00\x01\x01\x00\x00\x01\x00\x01\x00\x00" + sof + \
            bytes(r.randrange(256) for _ in range(200)) + b"\xff\xd9"
    elif kind == "gif":
        yield "gif-dims", b"GIF89a" + struct.pack("<HH", w & 0xFFFF, h & 0xFFFF) + b"\x00\x00\x00" + bytes(40)
    elif kind == "bmp":
        yield "bmp-dims", b"BM" + struct.pack("<IHHI", 54, 0, 0, 54) + struct.pack(
            "<IiiHHIIiiII", 40, w & 0x7FFFFFFF, -(h & 0x7FFFFFFF), 1, 24, 0, 0, 0, 0, 0, 0) + bytes(16)
    elif kind == "webp":
        yield "webp-dims", b"RIFF" + struct.pack("<I", 30) + b"WEBPVP8X" + struct.pack("<I", 10) + bytes(4) + \
            ((w - 1) & 0xFFFFFF).to_bytes(3, "little") + ((h - 1) & 0xFFFFFF).to_bytes(3, "little") + bytes(32)
    elif kind == "pnm":
        yield "pnm-dims", f"P6\n{w} {h}\n255\n".encode() + bytes(64)
    else:
        entries = [(256, 4, w), (257, 4, h), (258, 3, 8), (262, 3, 2), (273, 4, 8), (277, 3, 3)]
        ifd = struct.pack("<H", len(entries)) + b"".join(struct.pack("<HHII", t, k, 1, v & 0xFFFFFFFF)
                                                          for t, k, v in entries) + bytes(4)
        yield "tiff-dims", b"II*\x00" + struct.pack("<I", 8) + ifd + bytes(64)


def video_seeds(tmp: Path) -> dict[str, bytes]:
    from relightnet.io import VideoWriter

    g = np.random.default_rng(4)
    out = {}
    for suffix in (".mkv", ".mp4"):
        with VideoWriter(tmp / f"seed{suffix}", fps=10) as w:
            for _ in range(4):
                w.write(g.integers(0, 255, (24, 32, 3), dtype=np.uint8))
        out[suffix] = (tmp / f"seed{suffix}").read_bytes()
    return out


def video_cases(r: random.Random, seeds: dict[str, bytes]):
    """An mp4 whose sample description says huge (or zero) frame dimensions."""
    data = bytearray(seeds[".mp4"])
    at = data.find(b"avc1")
    w, h = r.choice(BIG_DIMS)
    if at > 0:
        data[at + 28:at + 32] = struct.pack(">HH", w & 0xFFFF, h & 0xFFFF)
    yield "mp4-dims", bytes(data)


def envmap_seeds(tmp: Path) -> dict[str, bytes]:
    from relightnet.io import write_envmap

    env = np.random.default_rng(5).uniform(0, 4, (8, 16, 3)).astype(np.float32)
    for s in (".exr", ".hdr"):
        write_envmap(tmp / f"seed{s}", env)
    return {s: (tmp / f"seed{s}").read_bytes() for s in (".exr", ".hdr")}


def envmap_cases(r: random.Random, seeds: dict[str, bytes]):
    w, h = r.choice(BIG_DIMS)
    if r.random() < 0.5:
        yield "hdr-dims", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w) + bytes(64)
    else:
        data = bytearray(seeds[".exr"])
        at = data.find(b"dataWindow\x00box2i\x00")
        if at > 0:
            box = at + len(b"dataWindow\x00box2i\x00") + 4
            data[box:box + 16] = struct.pack("<iiii", 0, 0, (w - 1) & 0x7FFFFFFF, (h - 1) & 0x7FFFFFFF)
        yield "exr-dims", bytes(data)


# --- checkpoints ---------------------------------------------------------------------------------------------------

NET = {"width": 4, "max_width": 8, "levels": 2, "light_hidden": 8}


def checkpoint_state() -> dict:
    import torch

    from relightnet.model import NetConfig, RelightNet

    torch.manual_seed(0)
    cfg = NetConfig(**NET)
    import dataclasses

    return {"format": "relightnet-ckpt-2", "net_config": dataclasses.asdict(cfg),
            "model": RelightNet(cfg).state_dict(), "step": 3, "input_size": 32}


def _torch_bytes(obj) -> bytes:
    import torch

    buf = io.BytesIO()
    torch.save(obj, buf)
    return buf.getvalue()


def checkpoint_cases(r: random.Random, base: dict):
    import torch

    state = {k: (dict(v) if isinstance(v, dict) else v) for k, v in base.items()}
    roll = r.choice(["net", "weights", "step", "missing", "format", "size", "object", "type"])
    if roll == "net":
        key = r.choice(list(state["net_config"]) + ["levels", "unknown"])
        state["net_config"][key] = r.choice([4096, 100000, -1, 2.5, "8", None, True, 10**20, [4]])
    elif roll == "weights":
        name = r.choice(list(state["model"]))
        t = state["model"][name]
        state["model"][name] = r.choice([torch.zeros(3), t.double(), t.half(), t * float("nan"), torch.zeros(()),
                                         t.to(torch.int64), t[:0], torch.zeros(*t.shape, 2)])
    elif roll == "step":
        state["step"] = r.choice([-1, "3", 2.5, None, [3], True])
    elif roll == "missing":
        state.pop(r.choice(["net_config", "model", "step"]))
    elif roll == "format":
        state["format"] = r.choice(["relightnet-ckpt-0", None, 2, "x"])
    elif roll == "size":
        state["input_size"] = r.choice([0, -16, 10**9, 16.0, "128", None])
    elif roll == "type":
        state = r.choice([[1, 2], "checkpoint", 5, None, {"model": state["model"]}])
    else:
        key = r.choice(["model", "net_config", "extra"])
        state[key] = r.choice([{"a": 1}, [torch.zeros(2)], "x", 3, (1, 2), {1: torch.zeros(1)}])
    yield "state", _torch_bytes(state)


# --- ONNX ------------------------------------------------------------------------------------------------------------

def onnx_seed(names=("image", "mask", "light_state", "is_first"), state_dims=(1, 9, 3)) -> bytes:
    """A small graph with the relightnet model's inputs and outputs (not its weights)."""
    from onnx import TensorProto, helper

    f = TensorProto.FLOAT
    inputs = [helper.make_tensor_value_info(names[0], f, ["B", 3, "H", "W"]),
              helper.make_tensor_value_info(names[1], f, ["B", 1, "H", "W"]),
              helper.make_tensor_value_info(names[2], f, ["B", *state_dims]),
              helper.make_tensor_value_info(names[3], TensorProto.BOOL, ["B"])]
    outputs = [helper.make_tensor_value_info(n, f, None)
               for n in ("albedo", "transport", "light_raw", "light_smoothed", "light_state_out")]
    nodes = [helper.make_node("Identity", [names[0]], ["albedo"]),
             helper.make_node("Mul", [names[0], names[1]], ["transport"]),
             helper.make_node("ReduceMean", [names[2]], ["light_raw"], axes=[1], keepdims=0),
             helper.make_node("Identity", ["light_raw"], ["light_smoothed"]),
             helper.make_node("Identity", [names[2]], ["light_state_out"])]
    model = helper.make_model(helper.make_graph(nodes, "g", inputs, outputs),
                              opset_imports=[helper.make_opsetid("", 13)])
    model.ir_version = 8
    return model.SerializeToString()


def onnx_cases(r: random.Random):
    roll = r.random()
    if roll < 0.4:
        names = ["image", "mask", "light_state", "is_first"]
        names[r.randrange(4)] = r.choice(["x", "image", ""]) or "y"
        if len(set(names)) < 4:
            names = ["image", "mask", "state", "is_first"]
        yield "names", onnx_seed(tuple(names))
    else:
        yield "state-dims", onnx_seed(state_dims=r.choice([("S", 9, 3), (1,), (), (0, 9, 3), (1, "K", 3),
                                                           (2**31, 9, 3)]))
