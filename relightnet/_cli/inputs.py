"""Inputs read by several commands before they call the library: one light, a photo with its mask."""

from __future__ import annotations

from ..errors import InputError

__all__ = ["load_single_light", "read_photo"]


def load_single_light(arg: str, lmax: int | None = None):
    """``load_light`` for options that take one light (K, 3), checked against physics
    (:func:`~relightnet.sh.io.check_light_physics`): a sequence is an error naming the option."""
    from ..light import load_light
    from ..sh.io import check_light_physics

    light = load_light(arg, lmax=lmax)
    if light.dim() != 2:
        raise InputError(f"--light {arg}: expected one light (K, 3), got a sequence {tuple(light.shape)}")
    return check_light_physics(light, arg)


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
            raise InputError(f"{what}: size {tuple(m.shape)} differs from the image's {tuple(img.shape[1:])}")
        if not m.any():
            raise InputError(f"{what}: empty mask (no person pixel): expected the person's mask")
    return img, m, alpha
