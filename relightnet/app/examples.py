"""The app's example photo: a person made by the data generator (no image ships with the package)."""

from __future__ import annotations

from pathlib import Path

__all__ = ["example_person"]


def example_person(folder, res: int = 256, seed: int = 7, index: int = 0) -> Path:
    """Render one generated person over its background and write it as ``example_<seed>_<index>.png``.

    Args:
        folder: where to write it (made if missing); an existing file is reused.
        res: side in pixels (a multiple of 16).
        seed, index: which generated sample.

    Returns:
        The PNG's path (8-bit sRGB, the composited image).
    """
    from ..data import SynthConfig
    from ..data.generate import generate_sample
    from ..io import write_image

    folder = Path(folder)
    path = folder / f"example_{seed}_{index}_{res}.png"
    if path.is_file():
        return path
    folder.mkdir(parents=True, exist_ok=True)
    cfg = SynthConfig(seed=seed, res=res, n_dirs=64, counts={"train": 0, "val": 0, "test": index + 1},
                      partial_crop_prob=0.0)
    sample = generate_sample(cfg, "test", index)
    write_image(path, sample.arrays["image_composite"], srgb=False)
    return path
