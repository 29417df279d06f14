"""Subcommand modules of the ``relightnet`` CLI (see :mod:`relightnet.cli`)."""
