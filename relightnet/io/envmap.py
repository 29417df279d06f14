"""High-dynamic-range environment maps (OpenEXR ``.exr``, Radiance ``.hdr``) via PyAV.

FFmpeg's ``exr`` and ``hdr`` decoders return planar float frames
(``gbrpf32le``, or ``gbrapf16le`` etc. for half-float/alpha EXRs) whose planes
are stored G, B, R[, A]; they are read plane by plane here and reordered to
R, G, B (no lossy swscale conversion). The tests check the order against a
hand-written uncompressed EXR whose pixels are known. Maps are returned as
``(H, W, 3)`` float32 linear radiance, channels-last, in the lat-long layout of
:mod:`relightnet.sh.directions`.

Writing: ``.exr`` is lossless float32 (FFmpeg's encoder, RLE compression);
``.hdr`` is RGBE (8-bit mantissa, about 1% relative precision, no negatives).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import av
import numpy as np
import torch

from ..checks import InputError, check_finite, check_shape
from .atomic import atomic_write
from .image import _decode_frame, _encode, _is_float_format

__all__ = ["ENVMAP_SUFFIXES", "read_envmap", "write_envmap"]

#: File name suffixes read and written as environment maps.
ENVMAP_SUFFIXES = (".exr", ".hdr")


def _float_planes_to_rgb(frame: av.VideoFrame, path) -> np.ndarray:
    """(H, W, 3) float32 R, G, B from a planar float frame, read plane by plane (no swscale).

    Handles ``gbrp[a]f{16,32}{le,be}`` (planes G, B, R[, A]) and ``grayf{16,32}{le,be}``.
    """
    name = frame.format.name
    m = re.fullmatch(r"(gbrap|gbrp|gray)f(16|32)(le|be)?", name)
    if m is None:
        raise InputError(f"{path}: unsupported float pixel format {name}")
    dtype = np.dtype(("<" if m.group(3) != "be" else ">") + ("f2" if m.group(2) == "16" else "f4"))
    h, w = frame.height, frame.width
    planes = []
    for p in frame.planes:
        a = np.frombuffer(p, dtype=dtype).reshape(-1, p.line_size // dtype.itemsize)
        planes.append(a[:h, :w].astype(np.float32))
    if m.group(1) == "gray":
        return np.stack([planes[0]] * 3, -1)
    return np.stack([planes[2], planes[0], planes[1]], -1)


def read_envmap(path: str | os.PathLike) -> torch.Tensor:
    """Read a lat-long HDR environment map.

    Args:
        path: ``.exr`` or ``.hdr`` file (any float image FFmpeg decodes).

    Returns:
        (H, W, 3) float32 linear RGB radiance; negative values clamped to 0.
        Gray maps are repeated to three channels, alpha is dropped.

    Raises:
        InputError: missing or unreadable file, not a floating-point image, or
            NaN/Inf pixels; the message names the file.
    """
    frame = _decode_frame(path, "an HDR environment map")
    name = frame.format.name
    if not _is_float_format(name):
        raise InputError(
            f"{path}: not an HDR environment map (decoded as {name}); expected a float .exr or .hdr"
        )
    arr = _float_planes_to_rgb(frame, path)
    env = torch.from_numpy(np.ascontiguousarray(arr, dtype=np.float32))
    if not bool(torch.isfinite(env).all()):
        raise InputError(f"{path}: environment map contains NaN or Inf pixels")
    return env.clamp_min_(0)


def write_envmap(path: str | os.PathLike, env: torch.Tensor) -> Path:
    """Write a lat-long HDR environment map atomically.

    Args:
        path: destination; ``.exr`` (lossless float32) or ``.hdr`` (RGBE,
            ~1% precision; negative values are written as 0).
        env: (H, W, 3) linear RGB radiance, tensor or array.

    Returns:
        The path written.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in ENVMAP_SUFFIXES:
        raise InputError(f"{path}: expected an environment-map file ending in {' or '.join(ENVMAP_SUFFIXES)}")
    env = torch.as_tensor(env)
    check_shape(env, ["H", "W", 3], name="env")
    if not env.is_floating_point():
        raise InputError(f"env: expected floating-point radiance, got {env.dtype}")
    check_finite(env, "env")
    if suffix == ".hdr":
        env = env.clamp_min(0)
    arr = np.ascontiguousarray(env.detach().cpu().numpy(), dtype=np.float32)
    frame = av.VideoFrame.from_ndarray(arr, format="gbrpf32le")  # takes R, G, B channels-last
    data = _encode(suffix[1:], frame)
    with atomic_write(path) as f:
        f.write(data)
    return path
