"""``blender-render`` on real hostile .blend files (made with bpy here), each run capped in a child process.

The resource checks: the file's own render size is held to ``--max-pixels``, its samples and
frames to the caps (or refused in one line naming the file); its scripts (an auto-run text block,
a Python driver) never run; within 2 GB; and a render killed mid-frame leaves nothing in OUT or
in TMPDIR. ``python tests/blender/hostile_blends.py NAME FOLDER`` prints one case's peak RSS.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import hostile_blends as hb  # noqa: E402

sys.path.pop(0)

pytestmark = pytest.mark.slow  # each case starts Blender in a capped child process

RSS_BUDGET = 2 << 30

REFUSED = {
    "blend-20000x20000-16.7M-spp-1e6-frames": "20000x20000 pixels (400.0 MP) is above the limit",
    "blend-16.7M-spp-at-1-percent": "asks for 16777216 Cycles samples per pixel",
    "blend-1e6-frames-with-spp-4": "asks for 1000000 frames",
    "blend-64x64-under-max-pixels-1000": "64x64 pixels (0.0 MP) is above the limit",
    "blend-subdivision-level-11": "ask for 25,165,824 faces",
    "blend-array-of-5e6": "ask for 30,000,000 faces",
    "blend-geometry-nodes": "a geometry-nodes modifier",
    "blend-4MP-denoised": "denoising a 2000x2000 render (4.0 MP) takes about 3.4 GiB",
}


def _run(name: str, folder: Path, wall: float = 120.0):
    case = hb.CASES[name](folder)
    res = hb.run_capped(case, folder, wall=wall)
    assert res.rss <= RSS_BUDGET, f"{name}: peak RSS {res.rss >> 20} MiB"
    assert not any((folder / m).exists() for m in hb.MARKERS), f"{name}: a script in the .blend ran"
    return case, res


@pytest.mark.parametrize("name", sorted(REFUSED))
def test_settings_above_the_limits_are_refused_in_one_line(tmp_path, name):
    case, res = _run(name, tmp_path)
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert res.rc == 1 and len(lines) == 1, res.stderr[-2000:]
    assert case.names in lines[0] and REFUSED[name] in lines[0] and "Error" in lines[0], lines[0]
    assert res.leftovers == [] and not (tmp_path / "out").exists()  # refused before OUT is made


@pytest.mark.parametrize("name", ["blend-capped-by-spp-and-frames", "blend-autorun-text-and-driver"])
def test_within_the_caps_one_frame_is_rendered_and_no_script_runs(tmp_path, name):
    from relightnet.io import read_envmap

    _, res = _run(name, tmp_path)
    assert res.rc == 0 and res.stderr.strip() == "", res.stderr[-2000:]  # not even the refused driver's lines
    assert res.leftovers == []
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["frame_00000.exr", "frame_00000.png"]
    exr = read_envmap(tmp_path / "out" / "frame_00000.exr")
    side = 200 if name.startswith("blend-capped") else 64  # 20000 at 1 %, or the file's own 64
    assert exr.shape == (side, side, 3) and float(exr.max()) > 0  # the lit cube


def test_a_render_killed_mid_frame_leaves_nothing_in_out_or_tmpdir(tmp_path):
    _, res = _run("blend-4MP-4096-spp-killed", tmp_path, wall=hb.KILL_AFTER)
    assert res.timed_out, f"the render ended by itself (exit {res.rc}): {res.stderr[-2000:]}"
    assert res.leftovers == []  # no staging folder or frame file in OUT, no blender_* folder in TMPDIR
    assert [p for p in (tmp_path / "out").rglob("*")] == []
    assert [p.name for p in (tmp_path / "_tmp").iterdir()] == []
