"""``python -m train`` ≡ ``relightnet train``; also the torchrun target (``torchrun ... -m train``)."""

import sys

from relightnet.cli import main

if __name__ == "__main__":
    sys.exit(main(["train", *sys.argv[1:]]))
