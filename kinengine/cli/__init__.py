"""The ``kinengine`` command line: :func:`main` (in :mod:`.main`) and one module per command. It uses
only kinengine's public API."""

from .main import build_parser, main

__all__ = ["build_parser", "main"]
