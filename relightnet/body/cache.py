"""Fill the Anny cache once: ``python -m relightnet.body.cache``.

Anny precomputes its MakeHuman-derived tensors on first use (minutes, ~800 MB)
into ``$ANNY_CACHE_DIR``. ``make`` runs this module once (into the checkout's
``.cache/anny``) so that tests, the demo and the installed ``relightnet`` command reuse
the cache: :func:`anny_cache_dir` finds it without the variable.
"""

from __future__ import annotations

import logging
import os
import time
import warnings
from pathlib import Path

logger = logging.getLogger(__name__)

#: Where ``make`` fills the cache: ``.cache/anny`` in the checkout the package is installed from.
PROJECT_CACHE = Path(__file__).resolve().parents[2] / ".cache" / "anny"


def anny_cache_dir() -> str | None:
    """Anny's cache folder: ``$ANNY_CACHE_DIR`` if set, else the checkout's ``.cache/anny`` when
    ``make`` filled it (an editable install, as ``make`` makes), else None (anny's own default,
    ``~/.cache/anny``)."""
    env = os.environ.get("ANNY_CACHE_DIR")
    if env:
        return env
    if (PROJECT_CACHE / ".filled").is_file():
        return str(PROJECT_CACHE)
    return None


def fill_anny_cache() -> float:
    """Build Anny's default full-body model once; return the seconds it took."""
    import anny

    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        anny.Anny()
    return time.perf_counter() - t0


def main() -> None:
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    logger.info("filling the Anny cache in %s", anny_cache_dir() or "~/.cache/anny")
    logger.info("Anny model ready in %.1f s", fill_anny_cache())


if __name__ == "__main__":
    main()
