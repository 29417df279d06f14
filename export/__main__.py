"""``python -m export [OPTIONS]`` ≡ ``relightnet export``; ``python -m export serve MODEL ...`` ≡
``relightnet onnx-run MODEL ...``. Run from the repository root (``-m`` finds this folder there)."""

import sys

from relightnet.cli import main

USAGE = """\
usage: python -m export [--checkpoint CKPT] --out MODEL.onnx [--smoothing ...] [--int8]   (relightnet export)
       python -m export serve MODEL.onnx --video CLIP --out-dir DIR [--masks ...]      (relightnet onnx-run)
'python -m export --help' and 'python -m export serve --help' list the options."""


def run(argv: list[str]) -> int:
    """Export (default) or serve (``serve`` first): the same parser and code as the relightnet command."""
    if argv[:1] == ["serve"]:
        return main(["onnx-run", *argv[1:]])
    if not argv:
        sys.stderr.write(USAGE + "\n")
        return 2
    return main(["export", *argv])


if __name__ == "__main__":
    sys.exit(run(sys.argv[1:]))
