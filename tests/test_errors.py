"""relightnet.errors: the exception classes, torch-free; an oversized photo is refused before torch loads."""

import struct
import subprocess
import sys
import zlib
from pathlib import Path

from relightnet import checks, errors

REPO = Path(__file__).resolve().parents[1]


def test_hierarchy_and_one_set_of_classes():
    assert issubclass(errors.ShapeError, errors.InputError)
    assert issubclass(errors.InputError, errors.RelightError) and issubclass(errors.InputError, ValueError)
    assert (checks.RelightError, checks.InputError, checks.ShapeError) == (
        errors.RelightError, errors.InputError, errors.ShapeError)


def _png(path: Path, w: int, h: int) -> None:
    """A PNG whose header says w x h (one compressed black row is enough: nothing is decoded)."""
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)

    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(b"\x00" + bytes(3 * w))) + chunk(b"IEND", b""))


def test_an_oversized_photo_is_refused_without_importing_torch(tmp_path):
    big = tmp_path / "big.png"
    _png(big, 12000, 12000)
    code = ("import sys; from relightnet.cli import main; "
            f"rc = main(['relight-image', {str(big)!r}, '--light', 'studio', '--out', {str(tmp_path / 'o.png')!r}]); "
            "print(rc, 'torch' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path,
                       env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin"})
    assert r.stdout.split() == ["1", "False"], r.stderr
    err = r.stderr.strip().splitlines()
    assert len(err) == 1 and "big.png: 12000x12000 pixels (144.0 MP) is above the limit" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.png"]
