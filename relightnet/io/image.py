"""8-bit images: sRGB transfer functions, PNG/JPEG/WebP writing and image reading.

Images are channels-last ``(H, W, C)`` tensors. Linear float images are
gamma-encoded (exact piecewise sRGB) only when written to 8-bit files.
Decoding uses PyAV (FFmpeg's decoders); PNG is written with FFmpeg's ``png`` encoder at a fast
compression level (the pixels are the same at any level), JPEG and WebP with Pillow; ICC
profiles are read and applied with Pillow's ImageCms; files are written atomically. Decoded
images are turned upright as their metadata says (a phone photo's EXIF
orientation, a phone video's rotation), and converted to sRGB from the ICC profile
they embed (:mod:`relightnet.io.icc`), so every reader returns what a viewer shows.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import av
import numpy as np
import torch

from ..checks import InputError, ShapeError, check_finite
from ..color import linear_to_srgb, srgb_to_linear
from .atomic import atomic_write
from .icc import check_profile, embed_icc, profile_to_srgb, read_icc, srgb_to_profile
from .limits import check_pixels, max_pixels
from .probe import IMAGE_OUT_SUFFIXES, PHOTO_SUFFIXES, check_image_file

__all__ = ["to_uint8", "write_image", "read_image", "read_image_alpha",
           "read_alpha", "read_mask"]

#: FFmpeg ``png`` encoder options: zlib level 2 with the "up" row filter writes a 5 MP photo about
#: 5× faster than the defaults (level 9, Paeth) for files within 1% of their size
PNG_OPTIONS = {"compression_level": "2", "pred": "up"}


def _as_hwc(img, name: str) -> torch.Tensor:
    img = torch.as_tensor(np.ascontiguousarray(img) if isinstance(img, np.ndarray) else img)
    if img.dim() == 2:
        img = img[..., None]
    if img.dim() != 3 or img.shape[-1] not in (1, 3):
        raise ShapeError(f"{name}: expected (H, W, 3) or (H, W, 1), got {tuple(img.shape)}")
    if img.shape[0] < 1 or img.shape[1] < 1:
        raise ShapeError(f"{name}: expected a non-empty image, got {tuple(img.shape)}")
    return img


def to_uint8(img, srgb: bool = True) -> torch.Tensor:
    """Quantise an image to 8 bits.

    Args:
        img: (H, W, C) float linear values (encoded with sRGB when ``srgb``,
            clamped to [0, 1], rounded) or uint8 (returned unchanged).
        srgb: apply :func:`linear_to_srgb` to float input.

    Returns:
        (H, W, C) uint8.
    """
    img = torch.as_tensor(img)
    if img.dtype == torch.uint8:
        return img
    if not img.is_floating_point():
        raise InputError(f"image: expected float (linear) or uint8 values, got {img.dtype}")
    check_finite(img, "image")
    x = linear_to_srgb(img.float()) if srgb else img.float()
    x = x.clamp(0, 1) if x is img else x.clamp_(0, 1)  # one temporary at most (a 12 MP frame is 144 MB)
    return x.mul_(255).round_().to(torch.uint8)


def _encode(codec: str, frame: av.VideoFrame, options: dict[str, str] | None = None) -> bytes:
    """Encode one frame with an FFmpeg image codec (and its ``options``) and return the file bytes."""
    ctx = av.CodecContext.create(codec, "w")
    ctx.width, ctx.height, ctx.pix_fmt = frame.width, frame.height, frame.format.name
    if options:
        ctx.options = dict(options)
    packets = list(ctx.encode(frame)) + list(ctx.encode(None))
    return b"".join(bytes(p) for p in packets)


def _is_float_format(name: str) -> bool:
    """True for FFmpeg float pixel formats (``gbrpf32le``, ``grayf32le``, ``rgbaf16le``, ...)."""
    return re.search(r"f(16|32)(le|be)?$", name) is not None


def decode_options() -> dict[str, str]:
    """FFmpeg decoder options that refuse frames above :func:`~relightnet.io.limits.max_pixels`.

    FFmpeg counts a frame's pixels with its sides padded for alignment (a 3605² PNG is 3616 ×
    3605 to it), so its limit gets 1/16 more: the exact limit is the header check
    (:func:`~relightnet.io.probe.check_image_file`); this one stops frames whose size only the
    decoder knows."""
    limit = max_pixels()
    return {"max_pixels": str(limit + limit // 16)}


def limit_hint() -> str:
    """What to add to a decoder error whose frame size was unknown: the pixel limit may be the cause."""
    return f"; frames above {max_pixels() / 1e6:.1f} MP are refused (--max-pixels, RELIGHTNET_MAX_PIXELS)"


def open_limited(path: str | os.PathLike, what: str):
    """``av.open`` a media file with the pixel limit applied to probing and decoding.

    The video stream's size from the container header is checked before any frame is
    decoded; FFmpeg's ``max_pixels`` makes its decoders refuse a larger frame anyway (for
    files whose header does not say). The caller closes the container.

    Raises:
        InputError: no video stream, or a frame size above the limit.
    """
    opts = decode_options()
    container = av.open(str(path), stream_options=[opts] * 64)
    try:
        if not container.streams.video:
            raise InputError(f"{path}: not {what} (no image stream)")
        ctx = container.streams.video[0].codec_context
        if ctx is None:  # a damaged header can name a codec FFmpeg does not have
            raise InputError(f"{path}: cannot read {what} (its image stream's codec is unknown or damaged)")
        if ctx.width or ctx.height:
            check_pixels(ctx.width, ctx.height, f"{path}")
        ctx.options = opts
    except BaseException:
        container.close()
        raise
    return container


def _decode_frame(path: str | os.PathLike, what: str) -> av.VideoFrame:
    """Decode the first video frame of ``path``; :class:`InputError` naming the file on failure.

    The size in the file's header is checked against the pixel limit before decoding; a damaged or
    truncated file is refused (the decoder's ``err_detect=explode``), never decoded in part.
    """
    path = Path(path)
    size = check_image_file(path, what)
    try:
        with open_limited(path, what) as container:
            # A truncated JPEG decodes without an error by default (its missing part flat green).
            container.streams.video[0].codec_context.options = {**decode_options(), "err_detect": "explode"}
            for frame in container.decode(video=0):
                return frame
    except InputError:
        raise
    except av.InvalidDataError:
        if path.stat().st_size == 0:
            raise InputError(f"{path}: is empty (0 bytes); expected {what}") from None
        if size is None:  # no header this package knows: perhaps not an image at all
            raise InputError(f"{path}: cannot read {what}: damaged, truncated or not an image (expected one of "
                             f"{', '.join(PHOTO_SUFFIXES)})") from None
        raise InputError(f"{path}: cannot read {what}: the file is damaged or truncated") from None
    except av.error.OverflowError:  # the decoder's own pixel limit (a size no header told)
        raise InputError(f"{path}: cannot read {what}{limit_hint()}") from None
    except (av.FFmpegError, OSError, ValueError) as e:
        hint = "" if size else limit_hint()
        raise InputError(f"{path}: cannot read {what} ({type(e).__name__}: {e}{hint})") from None
    raise InputError(f"{path}: not {what} (no frame decoded)")


def write_image(path: str | os.PathLike, img, srgb: bool = True, alpha=None, icc: bytes | None = None,
                quality: int = 92) -> Path:
    """Write an 8-bit PNG, JPEG or WebP atomically (by ``path``'s suffix).

    Args:
        path: destination ``.png`` (lossless), ``.jpg``/``.jpeg`` or ``.webp`` (lossy, ``quality``).
        img: (H, W, 3) or (H, W, 1) tensor or array; float values are linear
            radiance/reflectance (sRGB-encoded when ``srgb``, clamped to
            [0, 1]); uint8 values are written unchanged.
        srgb: gamma-encode float input with :func:`linear_to_srgb`.
        alpha: optional (H, W) coverage in [0, 1] (never gamma-encoded): an RGBA PNG or WebP (a
            JPEG has no alpha: ``InputError``).
        icc: optional ICC profile (the photo's, :func:`~relightnet.io.icc.photo_profile`): the sRGB
            pixels are converted into it and the file embeds it (:mod:`relightnet.io.icc`); ignored
            for a one-channel image without ``alpha``.
        quality: JPEG/WebP quality, 1 to 100 (ignored for PNG).

    Returns:
        The path written.

    Example:
        An 8-bit PNG round trip (uint8 pixels are written as they are):

        >>> import torch
        >>> from relightnet.io import read_image, write_image
        >>> img = torch.zeros(4, 6, 3, dtype=torch.uint8)
        >>> img[:, :3] = 255
        >>> write_image("half.png", img).name
        'half.png'
        >>> back = read_image("half.png")
        >>> back.shape, back[0, 0].tolist(), back[0, 5].tolist()
        (torch.Size([4, 6, 3]), [1.0, 1.0, 1.0], [0.0, 0.0, 0.0])
    """
    path = Path(path)
    kind = path.suffix.lower()
    if kind not in IMAGE_OUT_SUFFIXES:
        raise InputError(f"{path}: expected an output file ending in {', '.join(IMAGE_OUT_SUFFIXES)}")
    if kind in (".jpg", ".jpeg") and alpha is not None:
        raise InputError(f"{path}: a JPEG has no alpha channel; write the cut-out as .png or .webp")
    if type(quality) is not int or not 1 <= quality <= 100:
        raise InputError(f"quality: expected an integer from 1 to 100, got {quality!r}")
    img = to_uint8(_as_hwc(img, "image"), srgb)
    arr = np.ascontiguousarray(img.cpu().numpy())
    icc = check_profile(icc, path)
    if alpha is not None:
        a = torch.as_tensor(alpha).detach().cpu()
        if tuple(a.shape) != arr.shape[:2]:
            raise ShapeError(f"alpha: expected {arr.shape[:2]} like the image, got {tuple(a.shape)}")
        a8 = to_uint8(a.float()[..., None], srgb=False).numpy()
        rgb = np.repeat(arr, 3, axis=-1) if arr.shape[-1] == 1 else arr
        pixels = np.concatenate([srgb_to_profile(rgb, icc, path), a8], -1)
    elif arr.shape[-1] == 1:
        pixels, icc = arr[..., 0], None
    else:
        pixels = srgb_to_profile(arr, icc, path)
    pixels = np.ascontiguousarray(pixels)
    data = _png_bytes(pixels, icc) if kind == ".png" else _pillow_bytes(pixels, icc, kind, quality)
    with atomic_write(path) as f:
        f.write(data)
    return path


def _png_bytes(pixels: np.ndarray, icc: bytes | None) -> bytes:
    """(H, W) gray, (H, W, 3) RGB or (H, W, 4) RGBA uint8 -> PNG file bytes (with ``icc`` embedded)."""
    fmt = "gray" if pixels.ndim == 2 else ("rgba" if pixels.shape[-1] == 4 else "rgb24")
    data = _encode("png", av.VideoFrame.from_ndarray(pixels, format=fmt), PNG_OPTIONS)
    return data if icc is None else embed_icc(data, icc)


def _pillow_bytes(pixels: np.ndarray, icc: bytes | None, kind: str, quality: int) -> bytes:
    """The same pixels as JPEG (4:2:0) or WebP file bytes at ``quality``, with ``icc`` embedded."""
    import io

    from PIL import Image

    buf = io.BytesIO()
    extra = {"icc_profile": icc} if icc is not None else {}
    Image.fromarray(pixels).save(buf, "JPEG" if kind in (".jpg", ".jpeg") else "WEBP", quality=quality, **extra)
    return buf.getvalue()


def upright(arr: np.ndarray, rotation: float) -> np.ndarray:
    """Turn a decoded frame the way its display matrix says (EXIF orientation, video rotation).

    Args:
        arr: (H, W, ...) decoded pixels.
        rotation: the frame's counter-clockwise display rotation in degrees (PyAV's
            ``VideoFrame.rotation``, FFmpeg's ``av_display_rotation_get``); multiples of 90.

    Returns:
        (H, W, ...) or (W, H, ...) pixels as they are meant to be seen.
    """
    k = round(float(rotation) / 90) % 4
    return np.ascontiguousarray(np.rot90(arr, k)) if k else arr


def _exif_orientation(path: str | os.PathLike) -> int | None:
    """The EXIF orientation tag (1..8) of a JPEG file, or None (not a JPEG, no EXIF, no tag).

    FFmpeg reports an EXIF orientation as a display rotation only, which loses the mirrored
    orientations (2, 4, 5, 7); the tag itself keeps them.
    """
    import struct

    with open(path, "rb") as f:
        head = f.read(1 << 17)
    if head[:2] != b"\xff\xd8":
        return None
    i = 2
    while i + 4 <= len(head) and head[i] == 0xFF:
        marker, size = head[i + 1], struct.unpack(">H", head[i + 2:i + 4])[0]
        if marker == 0xDA:  # start of scan: no EXIF block before the pixels
            return None
        seg = head[i + 4:i + 2 + size]
        if marker == 0xE1 and seg[:6] == b"Exif\x00\x00" and seg[6:8] in (b"II", b"MM"):
            tiff, end = seg[6:], "<" if seg[6:8] == b"II" else ">"
            try:
                ifd = struct.unpack(end + "I", tiff[4:8])[0]
                for k in range(struct.unpack(end + "H", tiff[ifd:ifd + 2])[0]):
                    tag, _, _, value = struct.unpack(end + "HHIH", tiff[ifd + 2 + 12 * k:ifd + 12 + 12 * k])
                    if tag == 0x0112:
                        return value if 1 <= value <= 8 else None
            except struct.error:  # a truncated EXIF block: ignore it as viewers do
                return None
        i += 2 + size
    return None


def _orient(arr: np.ndarray, orientation: int) -> np.ndarray:
    """Apply an EXIF orientation (1..8) to (H, W, C) pixels."""
    turn = {1: arr, 2: arr[:, ::-1], 3: arr[::-1, ::-1], 4: arr[::-1], 5: arr.swapaxes(0, 1),
            6: np.rot90(arr, -1), 7: arr[::-1, ::-1].swapaxes(0, 1), 8: np.rot90(arr, 1)}[orientation]
    return np.ascontiguousarray(turn)


def _has_alpha(fmt: av.VideoFormat) -> bool:
    """True when a decoded pixel format can hold transparency: an alpha component (``rgba``,
    ``ya8``, ``yuva420p``, ...) or a palette (``pal8``, whose entries may be transparent)."""
    return fmt.name == "pal8" or any(c.is_alpha for c in fmt.components)


def _decode_pixels(path: str | os.PathLike, gray: bool = False) -> tuple[torch.Tensor, torch.Tensor | None]:
    """Decode an image, upright: its colour and its alpha where the file has transparency.

    Only a file whose own pixel format has transparency (:func:`_has_alpha`) is converted to
    RGBA; every other one goes to RGB (or gray) directly, never through RGBA: FFmpeg's YUV to
    RGBA conversion fills the right-hand columns of some 4:2:0 and 4:2:2 JPEGs (widths 1 to 4
    past a multiple of 16) with alpha 0 and wrong colours.

    Args:
        path: image file.
        gray: return one channel (the decoder's gray conversion) instead of RGB.

    Returns:
        ((H, W, 3) or, with ``gray``, (H, W, 1) float32 in [0, 1],
        (H, W) float32 alpha in [0, 1] or None when the file has no alpha or is fully opaque).
    """
    frame = _decode_frame(path, "an image")
    fmt = frame.format
    if _is_float_format(fmt.name):
        raise InputError(f"{path}: is a floating-point (HDR) image; read it with read_envmap")
    deep = max(c.bits for c in fmt.components) > 8
    scale = 65535.0 if deep else 255.0
    color, alpha = None, None
    if _has_alpha(fmt):
        rgba = frame.to_ndarray(format="rgba64le" if deep else "rgba")
        if bool((rgba[..., 3] < scale).any()):
            alpha = rgba[..., 3]
        if not gray:
            color = rgba[..., :3]
    if color is None:
        color = frame.to_ndarray(format=("gray16le" if deep else "gray") if gray else ("rgb48le" if deep else "rgb24"))
        color = color[..., None] if color.ndim == 2 else color
    if not gray:  # a mask's gray levels are not colours: no profile applies to them
        color = profile_to_srgb(color, read_icc(path), path)
    exif = _exif_orientation(path)

    def turn(arr: np.ndarray) -> torch.Tensor:
        arr = _orient(arr, exif) if exif is not None else upright(arr, frame.rotation)
        return torch.from_numpy(arr.astype(np.float32) / scale)

    return turn(color), (None if alpha is None else turn(alpha))


def read_image(path: str | os.PathLike, linear: bool = False) -> torch.Tensor:
    """Read an 8- or 16-bit image (PNG, JPEG, ...) as RGB floats, upright.

    Gray images are repeated to three channels; alpha is dropped (see :func:`read_image_alpha`).
    The EXIF orientation (rotations and mirrors) is applied, and an embedded ICC profile other
    than sRGB (Display-P3, Adobe RGB) is converted to sRGB (:mod:`relightnet.io.icc`).

    Args:
        path: image file.
        linear: decode sRGB to linear with :func:`srgb_to_linear`.

    Returns:
        (H, W, 3) float32 in [0, 1].

    Raises:
        InputError: missing, unreadable, or a floating-point (HDR) image
            (read those with :func:`relightnet.io.read_envmap`).
    """
    return read_image_alpha(path, linear)[0]


def read_image_alpha(path: str | os.PathLike, linear: bool = False) -> tuple[torch.Tensor, torch.Tensor | None]:
    """:func:`read_image` and the image's transparency from one decode.

    Returns:
        ((H, W, 3) float32 RGB, (H, W) float32 alpha in [0, 1] or None when the image has no
        alpha or is fully opaque).
    """
    x, a = _decode_pixels(path)
    return (srgb_to_linear(x) if linear else x), a


def read_alpha(path: str | os.PathLike) -> torch.Tensor | None:
    """The alpha channel of an image with transparency (e.g. a cut-out person), else None.

    Returns:
        (H, W) float32 in [0, 1], or None when the image has no alpha or is fully opaque.
    """
    return read_image_alpha(path)[1]


def read_mask(path: str | os.PathLike) -> torch.Tensor:
    """A person mask from an image file: its alpha where it has transparency, else white = person.

    A file without an alpha channel (a JPEG, an RGB or gray PNG) is read as one gray channel.

    Returns:
        (H, W) float32 in {0, 1} (alpha or gray level above 0.5).
    """
    gray, alpha = _decode_pixels(path, gray=True)
    return ((alpha if alpha is not None else gray[..., 0]) > 0.5).float()
