"""The command line's shared helpers, by concern (this module only gathers their names for the
commands that import them from here):

- :mod:`.argtypes`: argument types (``pos_int``, ``work_size``, ``key_value_arg``, ...);
- :mod:`.paths`: the output-path rule and input paths (``out_file``, ``out_dir``, ``in_path``,
  ``made_folders``);
- :mod:`.options`: options shared by commands (``add_command``, ``add_model_args``, ...);
- :mod:`.inputs`: inputs read before the library is called (``load_single_light``, ``read_photo``).

Nothing here imports torch at import time (see :mod:`relightnet.cli`).
"""

from __future__ import annotations

from ..deprecation import deprecated
from .argtypes import (
    exposure_arg,
    image_size,
    key_value_arg,
    nonneg_int,
    phenotype_arg,
    pos_float,
    pos_int,
    work_size,
)
from .inputs import load_single_light, read_photo
from .options import (
    LIGHT_HELP,
    MASK_SOURCE_HELP,
    add_body_args,
    add_command,
    add_mask_source_arg,
    add_model_args,
    check_method_options,
    method_options,
)
from .paths import in_path, made_folders, out_dir, out_file


@deprecated("0.1.0", "0.2.0", "add_model_args(p, backend=False)")
def add_checkpoint_args(p, device: bool = True) -> None:
    """--checkpoint (and --device): :func:`add_model_args` without --backend (kept while branches that
    call it are merged)."""
    add_model_args(p, backend=False, device=device)

__all__ = [
    "exposure_arg", "image_size", "key_value_arg", "nonneg_int", "phenotype_arg", "pos_float", "pos_int", "work_size",
    "load_single_light", "read_photo",
    "LIGHT_HELP", "MASK_SOURCE_HELP", "add_body_args", "add_command", "add_mask_source_arg", "add_model_args",
    "add_checkpoint_args", "check_method_options", "method_options",
    "in_path", "made_folders", "out_dir", "out_file",
]
