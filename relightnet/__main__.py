"""``python -m relightnet ...`` ≡ ``relightnet ...``, from any folder; also the torchrun target
(``torchrun --nproc-per-node 2 -m relightnet train ...``)."""

import sys

from relightnet.cli import main

if __name__ == "__main__":
    sys.exit(main())
