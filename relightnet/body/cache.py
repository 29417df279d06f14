"""Fill the Anny cache once: ``python -m relightnet.body.cache``.

Anny precomputes its MakeHuman-derived tensors on first use (minutes, ~800 MB)
into ``$ANNY_CACHE_DIR``. ``make`` runs this module once so that tests and the
demo reuse the cache.
"""

from __future__ import annotations

import logging
import os
import time
import warnings

logger = logging.getLogger(__name__)


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
    logger.info("filling the Anny cache in %s", os.environ.get("ANNY_CACHE_DIR", "~/.cache/anny"))
    logger.info("Anny model ready in %.1f s", fill_anny_cache())


if __name__ == "__main__":
    main()
