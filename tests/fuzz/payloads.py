"""Pickles that would create a file when loaded by an unrestricted unpickler (tests/fuzz).

Each payload targets a file in :data:`MARKERS` (set by the runner); the runner counts a
payload as executed when any file appears there. The payloads are built with plain
``pickle`` opcodes around real callables, so an unrestricted ``pickle.load`` /
``torch.load(weights_only=False)`` would run every one of them.
"""

from __future__ import annotations

import io
import os
import pickle
import shutil
import subprocess
from pathlib import Path

MARKERS = Path(".")


class _Call:
    """Pickles as ``func(*args)``."""

    def __init__(self, func, *args):
        self.func, self.args = func, args

    def __reduce__(self):
        return self.func, self.args


def _targets():
    m = lambda k: str(MARKERS / f"made-{k}")  # noqa: E731
    np = __import__("numpy")
    return [
        ("os.system", _Call(os.system, f"touch {m('system')}")),
        ("subprocess.Popen", _Call(subprocess.Popen, ["touch", m("popen")])),
        ("builtins.open", _Call(open, m("open"), "w")),
        ("builtins.exec", _Call(exec, f"open({m('exec')!r}, 'w').close()")),
        ("builtins.eval", _Call(eval, f"open({m('eval')!r}, 'w')")),
        ("pathlib.Path.touch", _Call(Path.touch, Path(m("touch")))),
        ("shutil.copyfile", _Call(shutil.copyfile, __file__, m("copy"))),
        ("io.FileIO", _Call(io.FileIO, m("fileio"), "w")),
        ("numpy.save", _Call(np.save, m("npsave"), np.zeros(1))),
        ("os.makedirs", _Call(os.makedirs, m("dir"))),
    ]


def payloads(kind: str):
    """(name, bytes) payloads: bare, hidden in a dict of arrays, in a list, in a nested dict."""
    import numpy as np

    for name, obj in _targets():
        wrapped = [obj, {"poses": obj, "betas": np.zeros(10)}, {"a": [1, {"b": (obj,)}]},
                   {"v_template": np.zeros((3, 3)), "f": obj}]
        for k, w in enumerate(wrapped):
            if kind == "torch":
                import torch

                buf = io.BytesIO()
                torch.save({"format": "relightnet-ckpt-2", "net_config": {}, "model": {}, "step": 0, "x": w}, buf)
                yield f"{name}#{k}", buf.getvalue()
            else:
                yield f"{name}#{k}", pickle.dumps(w, protocol=(0, 2, 4, 5)[k])
