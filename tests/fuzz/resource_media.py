"""Hostile small images and videos: decompression bombs, lying containers, large valid frames.

Part of the resource cases (``resource_cases.CASES`` gathers them): each function writes its
file(s) into a fresh folder and returns the ``relightnet`` command line that reads them.
GIF, WebP and TIFF "bombs" are tiny files that declare a huge canvas or hold thousands of
frames that are a few bytes each; mkv and webm files that claim far more frames or time than
they hold; a video whose frames are at the pixel limit. Nothing is committed as a file.
"""

from __future__ import annotations

import struct
import sys
import zlib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from resource_runner import Case  # noqa: E402

sys.path.pop(0)

# ---- files ----------------------------------------------------------------------------------


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def png(side: int, extra: bytes = b"", value: int = 128, height: int | None = None) -> bytes:
    """A side × height (default square) grey RGB PNG, compressed row by row; ``extra`` chunks go
    before the image data."""
    height = side if height is None else height
    z, row, parts = zlib.compressobj(9), b"\x00" + bytes([value]) * (3 * side), []
    for _ in range(height):
        parts.append(z.compress(row))
    parts.append(z.flush())
    return (b"\x89PNG\r\n\x1a\n" + _png_chunk(b"IHDR", struct.pack(">IIBBBBB", side, height, 8, 2, 0, 0, 0)) + extra
            + _png_chunk(b"IDAT", b"".join(parts)) + _png_chunk(b"IEND", b""))


def video(path: Path, n: int, side: int = 64) -> None:
    """An n-frame grey video (mp4 or mkv by its suffix)."""
    import numpy as np

    from relightnet.io import VideoWriter

    with VideoWriter(path, fps=30) as w:
        for i in range(n):
            w.write(np.full((side, side, 3), 20 * i, np.uint8))


def gif(width: int, height: int, frames: int, image: tuple[int, int] = (1, 1)) -> bytes:
    """A GIF whose screen is width × height with ``frames`` images of ``image`` pixels (a few bytes each)."""
    head = b"GIF89a" + struct.pack("<HHBBB", width, height, 0x80, 0, 0) + b"\x00\x00\x00\xff\xff\xff"
    frame = (b"\x21\xf9\x04\x00\x01\x00\x00\x00"  # graphic control: 1/100 s
             + b"," + struct.pack("<HHHHB", 0, 0, *image, 0) + b"\x02\x02\x44\x01\x00")
    return head + frame * frames + b";"


def _webp_1x1() -> bytes:
    """The VP8L chunk of a 1 × 1 lossless WebP (made by Pillow)."""
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.new("RGB", (1, 1), (200, 100, 50)).save(buf, "WEBP", lossless=True)
    data = buf.getvalue()
    return data[12:]


def webp_animated(width: int, height: int, frames: int) -> bytes:
    """An animated WebP: a width × height canvas (VP8X) with ``frames`` frames of 1 × 1 pixel."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return kind + struct.pack("<I", len(data)) + data + b"\x00" * (len(data) % 2)

    def u24(v: int) -> bytes:
        return int(v).to_bytes(3, "little")

    pixel = _webp_1x1()
    anmf = chunk(b"ANMF", u24(0) + u24(0) + u24(0) + u24(0) + u24(10) + b"\x00" + pixel)
    body = (b"WEBP" + chunk(b"VP8X", b"\x02\x00\x00\x00" + u24(width - 1) + u24(height - 1))
            + chunk(b"ANIM", b"\x00\x00\x00\x00\x00\x00") + anmf * frames)
    return b"RIFF" + struct.pack("<I", len(body)) + body


def tiff_pages(width: int, height: int, pages: int, loop: bool = False) -> bytes:
    """A grey TIFF of ``pages`` width × height pages sharing one deflated strip of zeros; with
    ``loop`` the last page's next-IFD offset points back to the first page."""
    strip = zlib.compress(bytes(width * height), 9)
    start = 8 + len(strip) + (len(strip) % 2)
    entries = [(256, 4, 1, width), (257, 4, 1, height), (258, 3, 1, 8), (259, 3, 1, 8), (262, 3, 1, 1),
               (273, 4, 1, 8), (277, 3, 1, 1), (278, 4, 1, height), (279, 4, 1, len(strip))]
    size = 2 + 12 * len(entries) + 4
    ifds = []
    for k in range(pages):
        nxt = start + (k + 1) * size if k + 1 < pages else (start if loop else 0)
        ifds.append(struct.pack("<H", len(entries)) + b"".join(struct.pack("<HHII", *e) for e in entries)
                    + struct.pack("<I", nxt))
    return b"II*\x00" + struct.pack("<I", start) + strip + b"\x00" * (len(strip) % 2) + b"".join(ifds)


def lying_matroska(path: Path, n: int = 8, side: int = 64, webm: bool = False, fps_ns: int | None = None,
                   box: int | None = None) -> None:
    """An n-frame mkv (ffv1) or webm (VP8) that claims 2·10⁹ frames (a NUMBER_OF_FRAMES tag) and a
    duration of 10¹⁵ ms (its Segment's Duration); ``fps_ns`` also sets its DefaultDuration (ns per
    frame). Its frames are a box in the middle, of value ``box`` (default: a grey that changes)."""
    from fractions import Fraction

    import av
    import numpy as np

    with av.open(str(path), "w", format="webm" if webm else "matroska") as c:
        s = c.add_stream("libvpx" if webm else "ffv1", rate=Fraction(10))
        s.width = s.height = side
        s.pix_fmt = "yuv420p" if webm else "bgr0"
        s.metadata["NUMBER_OF_FRAMES"] = "2000000000"
        for i in range(n):
            frame = np.zeros((side, side, 3), np.uint8)
            frame[side // 4:3 * side // 4, side // 3:2 * side // 3] = 60 + 20 * i if box is None else box
            for p in s.encode(av.VideoFrame.from_ndarray(frame, format="rgb24")):
                c.mux(p)
        for p in s.encode():
            c.mux(p)
    data = bytearray(path.read_bytes())
    for element, fmt in ((b"\x44\x89\x88", ">d"), (b"\x44\x89\x84", ">f")):  # Duration, a float of 8 or 4 bytes
        at = data.find(element)
        if at >= 0:
            data[at + 3:at + 3 + struct.calcsize(fmt)] = struct.pack(fmt, 1e15)
            break
    else:
        raise AssertionError(f"{path}: no Duration element to patch")
    if fps_ns is not None:
        at = data.find(b"\x23\xe3\x83\x84")  # DefaultDuration, 4 bytes
        data[at + 4:at + 8] = struct.pack(">I", fps_ns)
    path.write_bytes(bytes(data))


def mask_video(path: Path, n: int, side: int = 64) -> None:
    """An n-frame mask video (lossless mkv) of a box in the middle, the shape of :func:`lying_matroska`'s person."""
    import numpy as np

    from relightnet.io import VideoWriter

    with VideoWriter(path, fps=10) as w:
        for _ in range(n):
            m = np.zeros((side, side, 3), np.uint8)
            m[side // 4:3 * side // 4, side // 3:2 * side // 3] = 255
            w.write(m)


# ---- cases ----------------------------------------------------------------------------------


def _relight(folder: Path, photo: bytes, suffix: str = ".png", mask: bytes | None = None,
             expect: str = "error") -> Case:
    (folder / f"photo{suffix}").write_bytes(photo)
    (folder / "mask.png").write_bytes(png(16, value=255) if mask is None else mask)
    return Case(["relight-image", f"photo{suffix}", "--mask", "mask.png", "--light", "studio", "--out", "out.png"],
                f"photo{suffix}", expect=expect, outputs=("out.png",) if expect != "error" else ())


def _relight_video(folder: Path, data: bytes, suffix: str) -> Case:
    """``relight-video`` on a hostile file, the person found by the CNN's mask head (no other model)."""
    (folder / f"clip{suffix}").write_bytes(data)
    argv = ["-q", "relight-video", f"clip{suffix}", "--mask-source", "head", "--light", "studio", "--out", "out.mp4"]
    return Case(argv, f"clip{suffix}")


def _avatar(folder: Path, data: bytes, suffix: str) -> Case:
    """``avatar --target`` a hostile file with a given light (no light pass)."""
    (folder / f"target{suffix}").write_bytes(data)
    return Case(["-q", "avatar", "--target", f"target{suffix}", "--light", "studio", "--no-occlusion", "--n-dirs", "16",
                 "--out", "out.mp4"], f"target{suffix}")


def png_8000(folder: Path) -> Case:
    """A black 8000² PNG (about 270 KB): above the pixel limit, refused from its header."""
    return _relight(folder, png(8000, value=0))


def gif_bomb(folder: Path) -> Case:
    """A GIF whose screen is 16² but whose one image claims 65535² (a few dozen bytes)."""
    head = b"GIF89a" + struct.pack("<HHBBB", 16, 16, 0, 0, 0)
    image = b"," + struct.pack("<HHHHB", 0, 0, 65535, 65535, 0) + b"\x02\x02\x44\x01\x00;"
    return _relight(folder, head + image, ".gif")


def gif_screen(folder: Path) -> Case:
    """A GIF whose screen is 65535² with one 1 × 1 image (57 bytes): the decoder would paint the screen."""
    return _relight(folder, gif(65535, 65535, 1), ".gif")


def gif_frames_photo(folder: Path) -> Case:
    """A GIF of 3000² with 20,000 frames of one pixel (460 KB) as a photo: its first frame only is relit."""
    return _relight(folder, gif(3000, 3000, 20_000), ".gif", mask=png(3000, value=255), expect="ok")


def gif_frames_video(folder: Path) -> Case:
    """The same GIF as a video (20,000 frames of 9 MP from 460 KB): refused before the first frame."""
    return _relight_video(folder, gif(3000, 3000, 20_000), ".gif")


def gif_frames_target(folder: Path) -> Case:
    """The same GIF as an avatar's target video."""
    return _avatar(folder, gif(3000, 3000, 20_000), ".gif")


def gif_screen_video(folder: Path) -> Case:
    """The 65535² GIF screen as a video."""
    return _relight_video(folder, gif(65535, 65535, 3), ".gif")


def webp_bomb(folder: Path) -> Case:
    """A WebP (VP8X) canvas of 16384² (30 bytes)."""
    body = b"WEBP" + b"VP8X" + struct.pack("<I", 10) + b"\x00" * 4 + (16383).to_bytes(3, "little") * 2
    return _relight(folder, b"RIFF" + struct.pack("<I", len(body)) + body, ".webp")


def webp_anim_canvas_video(folder: Path) -> Case:
    """An animated WebP whose canvas is 16384² (3 frames of one pixel) as a video."""
    return _relight_video(folder, webp_animated(16384, 16384, 3), ".webp")


def webp_anim_frames_photo(folder: Path) -> Case:
    """An animated WebP of 3000² with 20,000 frames of one pixel (about 1 MB) as a photo."""
    return _relight(folder, webp_animated(3000, 3000, 20_000), ".webp", mask=png(3000, value=255), expect="any")


def webp_anim_frames_video(folder: Path) -> Case:
    """The same animated WebP as a video."""
    return _relight_video(folder, webp_animated(3000, 3000, 20_000), ".webp")


def tiff_bomb(folder: Path) -> Case:
    """A TIFF whose IFD says 100000 × 100000 pixels (under 100 bytes)."""
    entries = [(256, 4, 1, 100000), (257, 4, 1, 100000), (258, 3, 1, 8), (259, 3, 1, 1), (262, 3, 1, 1),
               (273, 4, 1, 8), (277, 3, 1, 1), (278, 4, 1, 100000), (279, 4, 1, 10**10 % 2**32)]
    ifd = struct.pack("<H", len(entries)) + b"".join(struct.pack("<HHII", *e) for e in entries) + b"\0" * 4
    return _relight(folder, b"II*\x00" + struct.pack("<I", 8) + ifd, ".tif")


def tiff_pages_photo(folder: Path) -> Case:
    """A TIFF of 20,000 pages of 3000² (a shared deflated strip: 1.3 MB) as a photo: its first page is read."""
    return _relight(folder, tiff_pages(3000, 3000, 20_000), ".tif", mask=png(3000, value=255), expect="any")


def tiff_ifd_loop(folder: Path) -> Case:
    """A two-page TIFF whose last page points back to the first (an endless chain of pages)."""
    return _relight(folder, tiff_pages(3000, 3000, 2, loop=True), ".tif", mask=png(3000, value=255), expect="any")


def tiff_pages_video(folder: Path) -> Case:
    """The 20,000-page TIFF as a video."""
    return _relight_video(folder, tiff_pages(3000, 3000, 20_000), ".tif")


def mkv_lying_target(folder: Path) -> Case:
    """An 8-frame mkv claiming 2·10⁹ frames and 10¹⁵ ms as an avatar's target: rendered for its 8 frames."""
    lying_matroska(folder / "target.mkv")
    argv = ["-q", "avatar", "--target", "target.mkv", "--light", "studio", "--no-occlusion", "--n-dirs", "16", "--out",
            "out.mp4"]
    return Case(argv, "target.mkv", expect="ok", outputs=("out.mp4", "out.lights.npz", "out.lights.png"))


def webm_lying_video(folder: Path) -> Case:
    """An 8-frame webm claiming 2·10⁹ frames and 10¹⁵ ms, relit with its (truthful) mask video."""
    lying_matroska(folder / "clip.webm", webm=True)
    mask_video(folder / "masks.mkv", 8)
    return Case(["-q", "relight-video", "clip.webm", "--masks", "masks.mkv", "--light", "studio", "--out", "out.mp4"],
                "clip.webm", expect="ok", outputs=("out.mp4",))


def mkv_lying_masks(folder: Path) -> Case:
    """A video and its mask video, both of 8 frames claiming 2·10⁹ and 10¹⁵ ms: paired by the frames really there."""
    lying_matroska(folder / "clip.mkv")
    lying_matroska(folder / "masks.mkv", box=255)
    return Case(["-q", "relight-video", "clip.mkv", "--masks", "masks.mkv", "--light", "studio", "--out", "out.mp4"],
                "masks.mkv", expect="ok", outputs=("out.mp4",))


def mkv_frame_rate_lie(folder: Path) -> Case:
    """An mkv whose DefaultDuration says 1 ns per frame (10⁹ frames per second) as an avatar's target."""
    lying_matroska(folder / "target.mkv", fps_ns=1)
    return Case(["-q", "avatar", "--target", "target.mkv", "--light", "studio", "--no-occlusion", "--n-dirs", "16",
                 "--out", "out.mp4"], "target.mkv")


def mask_video_short(folder: Path) -> Case:
    """An 8-frame video with a 5-frame mask video: refused before any frame is relit, nothing written."""
    lying_matroska(folder / "clip.mkv")
    mask_video(folder / "masks.mkv", 5)
    return Case(["-q", "relight-video", "clip.mkv", "--masks", "masks.mkv", "--light", "studio", "--out", "out.mp4"],
                "masks.mkv")


def mask_folder_bad_frame(folder: Path) -> Case:
    """An 8-frame video with 8 mask images, the fifth not an image: the run stops there and the half-made
    output is removed (nothing left)."""
    lying_matroska(folder / "clip.mkv")
    (folder / "masks").mkdir()
    for t in range(8):
        (folder / "masks" / f"{t:03d}.png").write_bytes(png(64, value=255) if t != 4 else b"\x89PNG garbage")
    return Case(["-q", "relight-video", "clip.mkv", "--masks", "masks", "--light", "studio", "--out", "out.mp4"],
                "004.png", outputs=tuple(f"masks/{t:03d}.png" for t in range(8)))


def photo_12mp(folder: Path) -> Case:
    """A valid 4000 × 3000 photo (12 MP, the largest common phone size): relit within the budget."""
    import numpy as np

    from relightnet.io import write_image

    (folder / "photo.png").write_bytes(png(4000, value=130, height=3000))
    mask = np.zeros((3000, 4000, 3), np.uint8)
    mask[500:2800, 1200:2800] = 255
    write_image(folder / "mask.png", mask, srgb=False)
    return Case(["relight-image", "photo.png", "--mask", "mask.png", "--light", "studio", "--out", "out.png"],
                "photo.png", expect="ok", outputs=("out.png",))


def _clip_at_limit(folder: Path, n: int = 8, w: int = 4000, h: int = 3120) -> None:
    """``clip.mp4`` and ``masks.mp4``: n frames of w × h (12.48 MP, just under the limit), a graded
    background with a box for the person that moves, and its masks."""
    import numpy as np

    from relightnet.io import VideoWriter

    ramp = (np.arange(w, dtype=np.uint16) * 200 // w + 20).astype(np.uint8)
    with VideoWriter(folder / "clip.mp4", fps=10) as clip, VideoWriter(folder / "masks.mp4", fps=10) as masks:
        for t in range(n):
            frame = np.empty((h, w, 3), np.uint8)
            frame[..., 0], frame[..., 1], frame[..., 2] = ramp, 120, 90
            mask = np.zeros((h, w, 3), np.uint8)
            box = (slice(h // 6, h * 5 // 6), slice(w // 3 + 20 * t, w * 2 // 3 + 20 * t))
            frame[box], mask[box] = (170, 130, 110), 255
            clip.write(frame)
            masks.write(mask)


def video_at_limit(folder: Path) -> Case:
    """8 frames of 4000 × 3120 (12.48 MP) relit with their mask video: within the budget."""
    _clip_at_limit(folder)
    return Case(["-q", "relight-video", "clip.mp4", "--masks", "masks.mp4", "--light", "studio", "--out", "out.mp4"],
                "clip.mp4", expect="ok", outputs=("out.mp4",))


def avatar_at_limit(folder: Path) -> Case:
    """An avatar put into 8 frames of 4000 × 3120 (12.48 MP), its silhouette antialiased: within the budget."""
    _clip_at_limit(folder)
    argv = ["-q", "avatar", "--target", "clip.mp4", "--light", "studio", "--no-occlusion", "--n-dirs", "16", "--out",
            "out.mp4"]
    return Case(argv, "clip.mp4", expect="ok", outputs=("out.mp4", "out.lights.npz", "out.lights.png", "masks.mp4"))


#: Cases that take more than a few seconds (a large frame relit or rendered): marked ``slow`` in the test.
SLOW = {"photo-12MP-relit", "gif-20000-frames-photo", "tiff-20000-pages-photo", "tiff-ifd-loop-photo",
        "video-12.5MP-relit", "avatar-12.5MP-target"}

CASES = {
    "png-8000x8000": png_8000,
    "gif-65535x65535-frame": gif_bomb,
    "gif-screen-65535x65535": gif_screen,
    "gif-screen-65535x65535-video": gif_screen_video,
    "gif-20000-frames-photo": gif_frames_photo,
    "gif-20000-frames-video": gif_frames_video,
    "gif-20000-frames-target": gif_frames_target,
    "webp-16384x16384": webp_bomb,
    "webp-anim-16384x16384-video": webp_anim_canvas_video,
    "webp-anim-20000-frames-photo": webp_anim_frames_photo,
    "webp-anim-20000-frames-video": webp_anim_frames_video,
    "tiff-100000x100000": tiff_bomb,
    "tiff-20000-pages-photo": tiff_pages_photo,
    "tiff-ifd-loop-photo": tiff_ifd_loop,
    "tiff-20000-pages-video": tiff_pages_video,
    "photo-12MP-relit": photo_12mp,
    "video-12.5MP-relit": video_at_limit,
    "avatar-12.5MP-target": avatar_at_limit,
    "mkv-claims-2e9-frames-target": mkv_lying_target,
    "webm-claims-2e9-frames-video": webm_lying_video,
    "mkv-mask-video-claims-2e9-frames": mkv_lying_masks,
    "mkv-1ns-per-frame-target": mkv_frame_rate_lie,
    "mask-video-5-of-8-frames": mask_video_short,
    "mask-folder-bad-5th-image": mask_folder_bad_frame,
}
