"""The kinengine command line: list, info, pose, verify, bench and show (one module per command).

Every sub-command handler takes the parsed arguments and returns an exit code;
kinengine errors are printed as one line and exit with status 2.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
import os
import re
import sys
import warnings


from .. import KinematicsError, __version__
from . import bench, catalog, info, pose, show, verify
from .arguments import summary


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="kinengine", description=summary(__doc__))
    parser.add_argument("--version", action="version", version=f"kinengine {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    for command in (catalog, info, pose, verify, bench, show):
        command.add_parser(sub)
    return parser


_VALUE_OPTIONS = ("--q", "--view")
_NEGATIVE_LIST = re.compile(r"-[0-9.]")


def join_negative_values(argv: Sequence[str]) -> list[str]:
    """['--q', '-0.5,0.2'] -> ['--q=-0.5,0.2']: argparse would read a leading minus as an option."""
    out: list[str] = []
    for arg in argv:
        if out and out[-1] in _VALUE_OPTIONS and _NEGATIVE_LIST.match(arg):
            out[-1] = f"{out[-1]}={arg}"
        else:
            out.append(arg)
    return out


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"kinengine: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(join_negative_values(sys.argv[1:] if argv is None else argv))
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warning
        try:
            return int(args.handler(args))
        except KinematicsError as exc:
            print(f"kinengine: error: {exc}", file=sys.stderr)
            return 2
        except BrokenPipeError:  # e.g. `kinengine pose ... | head`: the reader left, nothing to report
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 141
