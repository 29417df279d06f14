"""Helpers shared by subcommands."""

from __future__ import annotations

import argparse


def add_command(sub, name: str, help: str, examples: str) -> argparse.ArgumentParser:
    """Add a subcommand whose --help ends with copy-pasteable examples."""
    return sub.add_parser(
        name,
        help=help,
        description=help,
        epilog="examples:\n" + examples,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
