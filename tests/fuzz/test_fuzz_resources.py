"""Resource fuzzing: small hostile files end in one line or a correct output, within 2 GB and a wall cap.

Every case of ``resource_cases.CASES`` (SECURITY.md's table and variants) runs the real
``relightnet`` command in a child process whose address space is capped (``RLIMIT_AS``, so a
regression cannot take the machine) and which is killed after ``WALL_CAP`` seconds. The test
checks the exit status, the one-line error naming the hostile file, the child's peak RSS
(``os.wait4``) against the 2 GB budget, and that nothing was left in the case folder or the
child's ``TMPDIR``; a case with a ``check`` (the phone and stranger-file families of
``resource_phone.py`` and ``resource_phone_video.py``) then has its result checked too. Peak RSS
and time per case are printed by ``benchmarks/bench_untrusted.py --resources`` (BENCHMARKS.md,
SECURITY.md).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import resource_cases as rc  # noqa: E402
import resource_runner  # noqa: E402

sys.path.pop(0)


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in rc.SLOW else n
                                  for n in sorted(rc.CASES)])
def test_hostile_file_is_bounded(tmp_path, name):
    case = rc.CASES[name](tmp_path)
    res = rc.run_capped(case, tmp_path)
    assert not res.timed_out, f"{name}: still running after {rc.WALL_CAP} s"
    assert res.rss <= rc.RSS_BUDGET, f"{name}: peak RSS {res.rss >> 20} MiB"
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    if case.expect == "any" and res.rc == 0:  # read (a decoder that knows the format) or refused: both bounded
        pass
    elif case.expect in ("error", "any"):
        assert res.rc == 1, f"{name}: exit {res.rc}: {res.stderr[-2000:]}"
        assert len(lines) == 1, f"{name}: {len(lines)} lines on stderr: {res.stderr[-2000:]}"
        assert case.names in lines[0] and "Error" in lines[0] and len(lines[0]) < 400, lines[0]
    elif case.expect == "failed-jobs":  # a batch whose jobs all fail: status 1, each job's reason logged
        assert res.rc == 1, f"{name}: exit {res.rc}: {res.stderr[-2000:]}"
        assert "Traceback" not in res.stderr
    else:
        assert res.rc == 0, f"{name}: exit {res.rc}: {res.stderr[-2000:]}"
    assert res.leftovers == [], f"{name}: left {res.leftovers}"
    if case.check is not None:  # the result itself (resource_phone's families): what the output must be
        case.check(tmp_path)


@pytest.mark.slow
def test_the_caps_and_the_peak_are_real(tmp_path):
    """The child the cases run in cannot allocate beyond its cap, and its peak RSS is its own: a
    gigabyte more in this process does not change what the same command measures."""
    import subprocess

    script = resource_runner._CHILD.replace('runpy.run_module("relightnet.cli", run_name="__main__", alter_sys=True)',
                               f"b = bytearray({rc.AS_CAP})")
    proc = subprocess.run([sys.executable, "-c", script, str(rc.AS_CAP), str(tmp_path / "p"), "x"],
                          capture_output=True, text=True)
    assert proc.returncode == 1 and "MemoryError" in proc.stderr
    (tmp_path / "photo.png").write_bytes(rc.png(64))
    case = rc.Case(["light", "show", "studio", "--out", "s.png"], "", expect="ok", outputs=("s.png",))
    first = rc.run_capped(case, tmp_path)
    ballast = bytearray(1 << 30)
    ballast[:: 1 << 12] = b"\x01" * ((1 << 30) >> 12)  # touched: resident in this process
    second = rc.run_capped(case, tmp_path)
    assert first.rc == second.rc == 0, second.stderr
    assert 100 << 20 < first.rss < 1 << 30 and abs(second.rss - first.rss) < 64 << 20, (first.rss, second.rss)


def test_the_result_checks_refuse_wrong_results(tmp_path):
    """The families' checks (``Case.check``) fail on a wrong output: an RGBA or resized photo, a profile
    dropped, a grey person tinted, an input overwritten, an output left by a failed run."""
    from PIL import Image

    def case(prefix: str):
        name = next(n for n in sorted(rc.CASES) if n.startswith(prefix))
        folder = tmp_path / name
        folder.mkdir()
        return rc.CASES[name](folder), folder

    def refused(check, folder) -> None:
        with pytest.raises(AssertionError):
            check(folder)

    c, f = case("phone-width-")
    w, h = Image.open(f / "mask.png").size
    Image.new("RGBA", (w, h)).save(f / "out.png")
    refused(c.check, f)
    Image.new("RGB", (w + 1, h)).save(f / "out.png")
    refused(c.check, f)
    c, f = case("icc-p3-png")
    Image.new("RGB", Image.open(f / "mask.png").size).save(f / "out.png")
    refused(c.check, f)
    c, f = case("gray-rgb-png")
    Image.new("RGB", Image.open(f / "mask.png").size, (120, 118, 130)).save(f / "out.png")
    refused(c.check, f)
    Image.new("RGB", Image.open(f / "mask.png").size, (120, 121, 120)).save(f / "out.png")
    c.check(f)  # one level apart: grey
    c, f = case("out-is-input-hard-link")
    c.check(f)
    (f / "p.png").write_bytes(b"overwritten")
    refused(c.check, f)
    c, f = case("trunc-png-")
    c.check(f)
    (f / "out.png").write_bytes(b"half")
    refused(c.check, f)
