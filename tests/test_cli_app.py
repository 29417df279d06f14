"""`relightnet app`: its options (the page itself: tests/app)."""

import subprocess
import sys

import pytest

from relightnet.cli import build_parser


def test_port_option():
    parser = build_parser()
    assert parser.parse_args(["app"]).port == 7860
    assert parser.parse_args(["app", "--port", "8080"]).port == 8080
    for bad in ("-1", "70000", "http"):
        with pytest.raises(SystemExit):
            parser.parse_args(["app", "--port", bad])


def test_help_imports_neither_torch_nor_gradio():
    code = ("import sys; from relightnet.cli import main\n"
            "try:\n    main(['app', '--help'])\nexcept SystemExit:\n    pass\n"
            "print('torch' in sys.modules, 'gradio' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.strip().splitlines()[-1] == "False False"
    assert "127.0.0.1" in out.stdout
