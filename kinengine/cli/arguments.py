"""argparse value types shared by the sub-commands: bad values stop before any work is done."""

from __future__ import annotations

import argparse
import os
from pathlib import Path


def parse_vector(text: str) -> list[float]:
    """'0.1,-0.3,0.2' -> [0.1, -0.3, 0.2] (argparse type for --q)."""
    try:
        return [float(v) for v in text.replace(" ", "").split(",") if v]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None


def positive_int(text: str) -> int:
    """'20' -> 20; zero, negatives and non-integers are refused (argparse type for counts)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {value}")
    return value


def output_path(text: str) -> Path:
    """A file path whose folder exists and is writable (argparse type for --json, --plot, -o)."""
    path = Path(text)
    folder = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a folder; give a file name, e.g. {text.rstrip('/')}/out")
    if not folder.is_dir():
        raise argparse.ArgumentTypeError(f"cannot write {text!r}: folder {str(folder)!r} does not exist")
    if not os.access(folder, os.W_OK):
        raise argparse.ArgumentTypeError(f"cannot write {text!r}: folder {str(folder)!r} is not writable")
    return path


def summary(doc: str | None) -> str:
    """A module docstring's first line without reST markup, for --help."""
    return doc.splitlines()[0].replace("``", "") if doc else ""
