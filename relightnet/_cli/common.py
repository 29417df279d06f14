"""Helpers shared by subcommands: argument types, common options, and the output-path rule.

Nothing here imports torch at import time (see :mod:`relightnet.cli`).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import InputError
from ..names import MASK_SOURCES, MOTION_KINDS, POSE_PRESETS, light_presets


def add_command(sub, name: str, help: str, examples: str) -> argparse.ArgumentParser:
    """Add a subcommand whose --help ends with copy-pasteable examples."""
    return sub.add_parser(
        name,
        help=help,
        description=help,
        epilog="examples:\n" + examples,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )


LIGHT_HELP = (
    "a light: .npz/.json (relightnet), .npy (Kanamori-Endo, BGR), .exr/.hdr environment map, "
    f"a preset name ({', '.join(light_presets())}), "
    "or words: 'key:az=-40,el=30,size=20,color=1/0.9/0.8,power=3 + fill:az=60,power=0.5 + ambient:0.2'"
)


#: Folders :func:`out_file` / :func:`out_dir` made in this process, so that a command that
#: fails can remove the ones it left empty (:func:`remove_made_folders`).
_MADE: list[Path] = []


def _check_writable_parent(path: Path, option: str) -> None:
    """Make the missing parent folders of ``path``; an InputError naming ``option`` if that fails."""
    parent = path.parent
    missing = []
    q = parent
    while not q.exists() and q != q.parent:
        missing.append(q)
        q = q.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(f"{option} {path}: cannot make its folder {parent} ({e.strerror or e})") from None
    _MADE.extend(reversed(missing))


def forget_made_folders() -> None:
    """Start a command: folders made by an earlier command of this process are not its own."""
    _MADE.clear()


def remove_made_folders() -> None:
    """Remove the folders the output rule made that are still empty (after a failed command)."""
    while _MADE:
        try:
            _MADE.pop().rmdir()
        except OSError:
            pass


def in_path(path: str | Path, option: str, expected: str = "an existing file or folder") -> Path:
    """An input path that must exist, checked before any work.

    Raises:
        InputError: ``option PATH: not found (expected ...)``.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"{option} {p}: not found (expected {expected})")
    return p


def out_file(path: str | Path, option: str = "--out", suffixes: tuple[str, ...] | None = None) -> Path:
    """The output-file rule of every command, applied before any work.

    The file's type must be one of ``suffixes`` (case-insensitive; any if None), the path must
    not be an existing folder, and its missing parent folders are made. The file itself is
    written later, atomically, by the command.

    Returns:
        ``path`` as a Path.

    Raises:
        InputError: a wrong suffix, a folder at ``path``, or a parent folder that cannot be made.
    """
    p = Path(path)
    if suffixes is not None and p.suffix.lower() not in suffixes:
        raise InputError(f"{option} {p}: expected a file ending in {', '.join(suffixes)}")
    if p.is_dir():
        raise InputError(f"{option} {p}: is a folder; expected a file path")
    _check_writable_parent(p, option)
    return p


def out_dir(path: str | Path, option: str = "--out") -> Path:
    """The output-folder rule of every command, applied before any work.

    The path must not be an existing file; its missing parent folders are made (the folder
    itself is made by the command when it writes, so a run that fails early leaves none).

    Raises:
        InputError: a file at ``path``, or a parent folder that cannot be made.
    """
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise InputError(f"{option} {p}: is a file; expected a folder (made if needed)")
    _check_writable_parent(p, option)
    return p


def method_options(p: argparse.ArgumentParser, uses: dict[str, tuple[str, ...]]) -> None:
    """Record which methods each option of ``p`` applies to (``uses``: option dest → method names),
    for :func:`check_method_options` (call after the options are added: it reads their defaults)."""
    p.set_defaults(method_options={dest: (methods, p.get_default(dest)) for dest, methods in uses.items()})


def check_method_options(args: argparse.Namespace, method: str, option: str = "--smoothing") -> None:
    """Refuse an option given with a value for a method it does not apply to (it would be ignored)."""
    for dest, (methods, default) in getattr(args, "method_options", {}).items():
        if getattr(args, dest) != default and method not in methods:
            raise InputError(f"--{dest.replace('_', '-')}: applies to {option} {' / '.join(methods)}, "
                             f"not {method} (it would be ignored)")


def exposure_arg(text: str):
    if text == "auto":
        return text
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'auto' or a positive number, got {text!r}") from None
    if not v > 0:
        raise argparse.ArgumentTypeError(f"expected 'auto' or a positive number, got {text!r}")
    return v


def nonneg_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {text!r}") from None
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {text!r}")
    return v


def pos_int(text: str) -> int:
    v = nonneg_int(text)
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return v


def pos_float(text: str) -> float:
    """A finite number > 0."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not v > 0 or v == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


def _int_in(text: str, lo: int, hi: int, step: int, expected: str) -> int:
    """An integer in [lo, hi] that is a multiple of ``step``, else an argparse error saying ``expected``."""
    try:
        v = int(text)
    except ValueError:
        v = lo - 1
    if not lo <= v <= hi or v % step:
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
    return v


def work_size(text: str) -> int:
    """The CNN's working size: a positive multiple of 16, at most 2048."""
    return _int_in(text, 16, 2048, 16, "a multiple of 16 from 16 to 2048")


def image_size(text: str) -> int:
    """A picture's size in pixels: 1 to 4096."""
    return _int_in(text, 1, 4096, 1, "a size from 1 to 4096 pixels")


def key_value_arg(keys, cast, key_name: str = "NAME", value_name: str = "a number"):
    """An argparse type parsing ``KEY=VALUE`` with KEY in ``keys`` (a sequence or a callable giving one)."""

    def parse(text: str):
        names = keys() if callable(keys) else keys
        k, sep, v = text.partition("=")
        if not sep or k not in names:
            raise argparse.ArgumentTypeError(
                f"expected {key_name}=VALUE with {key_name} in {', '.join(names)}, got {text!r}"
            )
        try:
            return k, cast(v)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {value_name} after '{k}=', got {v!r}") from None

    return parse


def load_single_light(arg: str, lmax: int | None = None):
    """``load_light`` for options that take one light (K, 3): a sequence is an error naming the option."""
    from ..sh import load_light

    light = load_light(arg, lmax=lmax)
    if light.dim() != 2:
        raise InputError(f"--light {arg}: expected one light (K, 3), got a sequence {tuple(light.shape)}")
    return light


MASK_SOURCE_HELP = ("where the person's mask comes from when none is given (and a photo has no alpha): "
                    "'segment' (default): the shipped person segmentation; 'head': the CNN's mask head")


def add_mask_source_arg(p: argparse.ArgumentParser) -> None:
    """--mask-source segment|head: what finds the person when the user gives no mask."""
    p.add_argument("--mask-source", default="segment", choices=MASK_SOURCES, help=MASK_SOURCE_HELP)


def read_photo(image: str, mask: str | None, mask_source: str = "segment"):
    """A photo, its person mask and its alpha for the photo commands (the photo decoded once).

    The mask follows :mod:`relightnet.segment.sources`: ``--mask`` (its alpha where it has
    transparency, else white = person); without one, a cut-out photo's own alpha; else the
    person segmentation (``mask_source="segment"``) or None (``"head"``: the model's mask head).

    Returns:
        ((3, H, W) sRGB in [0, 1], (H, W) mask or None, (H, W) alpha or None).
    """
    from ..io.probe import check_image_file

    check_image_file(image, "an image")  # an oversized photo is refused before torch loads
    if mask:
        check_image_file(mask, "a mask image")
    from ..io import read_image_alpha, read_mask
    from ..segment.sources import person_mask

    img, alpha = read_image_alpha(image)
    img = img.permute(2, 0, 1)
    given = read_mask(mask) if mask else None
    m = person_mask(img, given, alpha, mask_source, name=image)
    if given is not None or alpha is not None:  # the user's mask or the photo's alpha: check it fits
        what = f"--mask {mask}" if mask else f"{image}: alpha channel"
        if tuple(m.shape) != tuple(img.shape[1:]):
            raise ValueError(f"{what}: size {tuple(m.shape)} differs from the image's {tuple(img.shape[1:])}")
        if not m.any():
            raise ValueError(f"{what}: empty mask (no person pixel): expected the person's mask")
    return img, m, alpha


def add_checkpoint_args(p: argparse.ArgumentParser, device: bool = True) -> None:
    """--checkpoint (and --device): which CNN, on which torch device."""
    p.add_argument("--checkpoint", help="model checkpoint (default: the shipped model)")
    if device:
        p.add_argument("--device", default="cpu", help="cpu or cuda (default: cpu)")


def add_model_args(p: argparse.ArgumentParser) -> None:
    """--checkpoint, --backend and --device: where the CNN comes from and runs."""
    p.add_argument("--checkpoint", help="model checkpoint (.pt; or .onnx with --backend onnx; "
                   "default: the shipped model)")
    p.add_argument("--backend", default="torch", choices=("torch", "onnx"),
                   help="run the CNN in PyTorch or in ONNX Runtime (exported once and cached; default: torch)")
    p.add_argument("--device", default="cpu", help="cpu or cuda (torch backend; default: cpu)")


def _phenotypes():
    from ..body import PHENOTYPES

    return PHENOTYPES


#: ``--phenotype NAME=VALUE`` for Anny (names from relightnet.body.PHENOTYPES).
phenotype_arg = key_value_arg(_phenotypes, float, "NAME", "a number")


def add_body_args(p: argparse.ArgumentParser, fps_help: str = "video frame rate (default: 30)") -> None:
    """--body, --pose, --motion, --frames, --fps, --phenotype: the posed body of render-body and blender-export."""
    p.add_argument("--body", default="anny", help="'anny' (default) or 'smpl:PATH' to a user-supplied SMPL file")
    p.add_argument("--pose", default="arms_down", choices=POSE_PRESETS, metavar="POSE",
                   help=f"pose preset of a still Anny body: {', '.join(POSE_PRESETS)} (default: arms_down)")
    p.add_argument("--motion", help=f"procedural motion for Anny ({', '.join(MOTION_KINDS)}) or an SMPL-style "
                   "motion file (.npz/.pkl with poses (T,72), betas (10,), trans (T,3)) for --body smpl:PATH")
    p.add_argument("--frames", type=pos_int, default=60, help="frames of a procedural motion (default: 60)")
    p.add_argument("--fps", type=float, default=30.0, help=fps_help)
    p.add_argument("--phenotype", type=phenotype_arg, action="append", metavar="NAME=VALUE",
                   help="Anny phenotype value (gender, age, muscle, weight, height, proportions); repeatable")
