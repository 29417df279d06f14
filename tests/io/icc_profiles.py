"""ICC v2 matrix/TRC display profiles built from primaries, for tests (Pillow creates sRGB and LAB only).

The colorants are the RGB → XYZ matrix's columns adapted from the white point to the ICC's D50 with
the Bradford transform, as ICC display profiles store them; the tone curves are ``curv`` tables.
"""

import struct

import numpy as np

D50 = np.array([0.9642, 1.0, 0.8249])
BRADFORD = np.array([[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]])
P3 = ((0.680, 0.320), (0.265, 0.690), (0.150, 0.060))
SRGB = ((0.640, 0.330), (0.300, 0.600), (0.150, 0.060))
D65 = (0.3127, 0.3290)


def _xyz(xy) -> np.ndarray:
    x, y = xy
    return np.array([x / y, 1.0, (1 - x - y) / y])


def rgb_to_xyz(primaries, white=D65) -> np.ndarray:
    """(3, 3) linear RGB → XYZ (Y of white = 1) of a colour space."""
    p = np.stack([_xyz(c) for c in primaries], 1)
    return p * np.linalg.solve(p, _xyz(white))


def srgb_curve(n: int = 4096) -> np.ndarray:
    """The sRGB decoding curve sampled at ``n`` points of [0, 1]."""
    c = np.linspace(0, 1, n)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _s15(v) -> bytes:
    return b"".join(struct.pack(">i", round(float(x) * 65536)) for x in v)


def _tag_desc(text: str) -> bytes:
    a = text.encode("ascii") + b"\x00"
    return b"desc" + bytes(4) + struct.pack(">I", len(a)) + a + bytes(4 + 4 + 2 + 1 + 67)


def matrix_profile(primaries, white=D65, curve=None, description: str = "test RGB") -> bytes:
    """An ICC v2 monitor profile (RGB, XYZ connection space) of a matrix/TRC colour space.

    Args:
        primaries: ((xr, yr), (xg, yg), (xb, yb)) chromaticities.
        white: the white point's (x, y).
        curve: (n,) the decoding curve on [0, 1] (default :func:`srgb_curve`); n = 1 holds a gamma.
    """
    w = _xyz(white)
    adapt = np.linalg.inv(BRADFORD) @ np.diag((BRADFORD @ D50) / (BRADFORD @ w)) @ BRADFORD
    m = adapt @ rgb_to_xyz(primaries, white)
    curve = srgb_curve() if curve is None else np.asarray(curve, dtype=float)
    if curve.size == 1:
        curv = b"curv" + bytes(4) + struct.pack(">IH", 1, round(float(curve[0]) * 256)) + bytes(2)
    else:
        table = np.clip(np.round(curve * 65535), 0, 65535).astype(">u2").tobytes()
        curv = b"curv" + bytes(4) + struct.pack(">I", curve.size) + table + bytes(-len(table) % 4)
    tags = [(b"desc", _tag_desc(description)), (b"cprt", b"text" + bytes(4) + b"none\x00\x00\x00\x00"),
            (b"wtpt", b"XYZ " + bytes(4) + _s15(D50))]
    tags += [(sig, b"XYZ " + bytes(4) + _s15(m[:, i])) for i, sig in enumerate((b"rXYZ", b"gXYZ", b"bXYZ"))]
    tags += [(sig, curv) for sig in (b"rTRC", b"gTRC", b"bTRC")]
    offset = 128 + 4 + 12 * len(tags)
    table, data = struct.pack(">I", len(tags)), b""
    for sig, body in tags:
        body += bytes(-len(body) % 4)
        table += sig + struct.pack(">II", offset + len(data), len(body))
        data += body
    size = offset + len(data)
    header = (struct.pack(">I", size) + b"lcms" + struct.pack(">I", 0x02100000) + b"mntrRGB XYZ "
              + struct.pack(">6H", 2024, 1, 1, 0, 0, 0) + b"acsp" + bytes(4) + bytes(4) + bytes(8) + bytes(8)
              + struct.pack(">I", 0) + _s15(D50) + bytes(4))
    header += bytes(128 - len(header))
    return header + table + data


def display_p3() -> bytes:
    """Display-P3: the P3 primaries, D65 white and the sRGB curve (a phone photo's profile)."""
    return matrix_profile(P3, D65, description="Display P3 (test)")
