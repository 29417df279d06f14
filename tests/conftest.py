"""Fixtures shared by every test folder: the Anny cache location, one Anny model per test run, and the
``--device`` / ``--dtype`` options (fixtures ``device``, ``dtype``) of the kernel tests."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

# `make test` exports ANNY_CACHE_DIR; a bare `pytest` run uses the same repo cache.
os.environ.setdefault("ANNY_CACHE_DIR", str(Path(__file__).resolve().parents[1] / ".cache" / "anny"))
os.environ.setdefault("MPLBACKEND", "Agg")


def _inductor_cache() -> str:
    """torch.compile's kernel cache, one folder per processor and ATen capability. A kernel cached
    under one capability (AVX-512) and reused under another (ATEN_CPU_CAPABILITY=avx2, the stand-in for
    an AVX2-only CPU; or a cache carried to another machine) crashed the process (segfault in
    tests/raster/test_rasterize.py::test_compiled_kernels_match_eager)."""
    import hashlib

    try:
        with open("/proc/cpuinfo") as f:
            flags = next((ln for ln in f if ln.startswith("flags")), "")
    except OSError:
        flags = ""
    key = hashlib.sha256((flags + os.environ.get("ATEN_CPU_CAPABILITY", "")).encode()).hexdigest()[:12]
    return str(Path(__file__).resolve().parents[1] / ".cache" / "inductor" / key)


os.environ.setdefault("TORCHINDUCTOR_CACHE_DIR", _inductor_cache())


def _cpu_line() -> str:
    import platform

    import torch

    model = platform.processor()
    try:
        with open("/proc/cpuinfo") as f:
            model = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), model)
    except OSError:
        pass
    return (f"CPU: {model}; torch {torch.__version__} capability {torch.backends.cpu.get_cpu_capability()}, "
            f"{torch.get_num_threads()} threads")


_CPU_LINE: list[str] = []  # taken at the start: tests change torch's thread count on the way


def pytest_sessionstart():
    _CPU_LINE.append(_cpu_line())


def pytest_report_header(config):
    """The processor the suite runs on, as torch sees it (a red run on another CPU says which)."""
    return _CPU_LINE[0] if _CPU_LINE else _cpu_line()


def pytest_terminal_summary(terminalreporter):
    """The same line at the end, where ``-q`` (``make test``) shows it too."""
    terminalreporter.write_line(_CPU_LINE[0] if _CPU_LINE else _cpu_line())


def pytest_addoption(parser):
    group = parser.getgroup("relightnet")
    group.addoption("--device", default="cpu",
                    help="torch device of the kernel tests (SH, rasterizer, renderer, PRT): cpu (default), cuda, "
                         "cuda:N; `make test PYTEST_ARGS=\"--device cuda\"` on a GPU machine")
    group.addoption("--dtype", default="float32", choices=("float32", "float64"),
                    help="floating-point type of the kernel tests (default: float32)")


@pytest.fixture(scope="session")
def device(request):
    """The torch.device the kernel tests run on (``--device``); a missing CUDA is a usage error."""
    import torch

    name = request.config.getoption("--device")
    try:
        dev = torch.device(name)
    except RuntimeError as e:
        raise pytest.UsageError(f"--device {name}: {e}") from None
    if dev.type == "cuda" and not torch.cuda.is_available():
        raise pytest.UsageError(f"--device {name}: this torch build or machine has no CUDA device")
    return dev


@pytest.fixture(scope="session")
def dtype(request):
    """The torch dtype of the kernel tests (``--dtype``)."""
    import torch

    return getattr(torch, request.config.getoption("--dtype"))


@pytest.fixture(scope="session")
def anny_body():
    """The default AnnyBody (float32, feet on y = 0), built once per test run."""
    from relightnet.body import AnnyBody

    return AnnyBody()


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory, anny_body):
    """A real dataset folder made by the generator: 6 train and 3 test samples at 32², 16 PRT directions."""
    from relightnet.data import SynthConfig
    from relightnet.data.synth import run_synth

    out = tmp_path_factory.mktemp("data") / "tiny"
    cfg = SynthConfig(seed=3, res=32, n_dirs=16, shard_size=4, counts={"train": 6, "test": 3})
    run_synth(out, cfg, workers=0, progress=False, body=anny_body)
    return out


@pytest.fixture
def masked_clip():
    """``masked_clip(folder, n=3, h=64, w=48)`` → (lossless video, mask folder): a bright block moving
    one pixel per frame over a random background, with its masks."""

    def make(folder, n=3, h=64, w=48):
        import numpy as np

        from relightnet.io import VideoWriter, write_image

        video, masks = folder / "clip.mkv", folder / "masks"
        masks.mkdir()
        g = np.random.default_rng(0)
        with VideoWriter(video, fps=12) as v:
            for t in range(n):
                img = g.integers(40, 90, (h, w, 3), dtype=np.uint8)
                img[8 : h - 8, 14 + t : 30 + t] = 180
                m = np.zeros((h, w, 3), np.uint8)
                m[8 : h - 8, 14 + t : 30 + t] = 255
                v.write(img)
                write_image(masks / f"{t:03d}.png", m)
        return video, masks

    return make


@pytest.fixture
def clip_with_sound():
    """``clip_with_sound(path, acodec="aac", fmt="mp4")`` → a 2 s, 10 fps, 64x48 clip with a 440 Hz
    stereo tone."""
    import av
    import numpy as np

    def make(path, acodec="aac", fmt="mp4", seconds=2.0, fps=10, rate=22050):
        """A 64x48 clip at ``fps`` with a 440 Hz stereo tone encoded with ``acodec``."""
        c = av.open(str(path), "w", format=fmt)
        v = c.add_stream("libx264", rate=fps)
        v.width, v.height, v.pix_fmt = 64, 48, "yuv420p"
        a = c.add_stream(acodec, rate=rate, layout="stereo")
        for i in range(int(seconds * fps)):
            for p in v.encode(av.VideoFrame.from_ndarray(np.full((48, 64, 3), 10 * i, np.uint8), format="rgb24")):
                c.mux(p)
        tone = (0.3 * np.sin(2 * np.pi * 440 * np.arange(int(seconds * rate)) / rate)).astype(np.float32)
        resampler = av.AudioResampler(format=a.codec_context.format.name, layout="stereo", rate=rate)
        for k in range(0, len(tone), 1024):
            frame = av.AudioFrame.from_ndarray(np.stack([tone[k:k + 1024]] * 2), format="fltp", layout="stereo")
            frame.sample_rate, frame.pts = rate, k
            for f in resampler.resample(frame):
                for p in a.encode(f):
                    c.mux(p)
        for p in [*a.encode(None), *v.encode(None)]:
            c.mux(p)
        c.close()
        return path

    return make


#: Markers given by what a test uses (pyproject.toml registers them; docs/design.md, "Tests"):
#: a test that takes one of these fixtures, or lives in one of these folders, gets the marker.
FIXTURE_MARKERS = {
    "ray_cluster": "ray",
    "exported": "slow",  # a network exported to ONNX with dynamo (tests/model/conftest.py), ~10 s
    "generated_people": "slow",  # people made by the generator at 256² (tests/segment/conftest.py), ~10 s
}
FOLDER_MARKERS = {"blender": "blender"}


def pytest_collection_modifyitems(config, items):
    root = Path(__file__).resolve().parent
    for item in items:
        for fixture, marker in FIXTURE_MARKERS.items():
            if fixture in getattr(item, "fixturenames", ()):
                item.add_marker(marker)
        parts = Path(str(item.fspath)).resolve().relative_to(root).parts
        if len(parts) > 1 and parts[0] in FOLDER_MARKERS:
            item.add_marker(FOLDER_MARKERS[parts[0]])
