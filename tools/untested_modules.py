"""List the modules of relightnet/ without a mirrored test file.

The rule (README, docs/design.md): ``relightnet/<sub>/<module>.py`` is tested in
``tests/<sub>/test_<module>.py`` (``relightnet/<module>.py`` in ``tests/test_<module>.py``;
``relightnet/_cli/<name>.py``, the command line, in ``tests/test_cli_<name>.py`` or
``tests/<sub>/test_cli_<name>.py``). ``__init__.py`` and ``__main__.py`` are covered by
``tests/test_api.py`` and the CLI tests.

    python tools/untested_modules.py          # prints one module per line; exit 1 if any
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def mirror_names(module: Path) -> list[str]:
    """Test file names (relative to tests/) that count as the mirror of ``module``."""
    rel = module.relative_to(ROOT / "relightnet")
    if rel.parts[0] == "_cli":
        return [f"test_cli_{rel.stem}.py", f"*/test_cli_{rel.stem}.py"]
    return [str(rel.parent / f"test_{rel.stem}.py")]


def untested() -> list[str]:
    tests = {str(p.relative_to(ROOT / "tests")) for p in (ROOT / "tests").rglob("test_*.py")}
    missing = []
    for module in sorted((ROOT / "relightnet").rglob("*.py")):
        if module.name in ("__init__.py", "__main__.py"):
            continue
        names = mirror_names(module)
        found = any(t == n or (n.startswith("*/") and t.endswith(n[1:])) for n in names for t in tests)
        if not found:
            missing.append(str(module.relative_to(ROOT)))
    return missing


if __name__ == "__main__":
    rows = untested()
    print("\n".join(rows) if rows else "every module has its mirrored test file")
    sys.exit(1 if rows else 0)
