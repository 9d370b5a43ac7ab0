"""The kinengine command line: list, info, pose, verify, bench and show (one module per command).

Every sub-command handler takes the parsed arguments and returns an exit code. Every bad input
ends in one line on stderr, ``kinengine: error: ...``, and exit status 2: argparse's own errors
(:class:`~kinengine.cli.arguments.OneLineParser`), kinengine errors, an output that cannot be
written (a full disk, /dev/full as stdout) and memory that runs out. Names are printed with their
control characters escaped; stdout and stderr escape what their encoding cannot show
(``PYTHONIOENCODING=ascii``). An unexpected exception is one line too, with exit status 1.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import sys
import warnings
from collections.abc import Sequence
from typing import TextIO

from .. import KinematicsError, __version__, accelerator_status
from . import bench, catalog, info, pose, show, verify, view
from .arguments import OneLineParser, one_line, summary


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="kinengine", description=summary(__doc__))
    parser.add_argument(
        "--version",
        action=_Version,
        nargs=0,
        help="the version and whether the C accelerator is on, then exit",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    for command in (catalog, info, pose, verify, bench, show, view):
        command.add_parser(sub)
    return parser


class _Version(argparse.Action):
    """--version: two lines as written (argparse's own version action would re-wrap them into one)."""

    def __call__(self, parser: argparse.ArgumentParser, *args: object) -> None:
        print(f"kinengine {__version__}\n{accelerator_status()}")
        parser.exit()


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


def _one_line_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: TextIO | None = None,
    line: str | None = None,
) -> None:
    print(f"kinengine: warning: {one_line(message)}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    for stream in (sys.stdout, sys.stderr):  # e.g. PYTHONIOENCODING=ascii and a robot named "bras_é"
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    args = build_parser().parse_args(join_negative_values(sys.argv[1:] if argv is None else argv))
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warning
        try:
            code = int(args.handler(args))
            sys.stdout.flush()  # a full disk or /dev/full as stdout fails here, not at exit
            return code
        except KinematicsError as exc:
            return _error(exc)
        except BrokenPipeError:  # e.g. `kinengine pose ... | head`: the reader left, nothing to report
            _silence_stdout()
            return 141
        except OSError as exc:
            where = f" {exc.filename!r}" if exc.filename else " the output"
            return _error(f"cannot write{where}: {exc.strerror or exc}", silence=True)
        except MemoryError:
            return _error("out of memory; use a smaller model, fewer samples or a lower resolution")
        except KeyboardInterrupt:
            return 130
        except Exception as exc:  # a bug: still one line, and a distinct exit status
            print(f"kinengine: internal error: {type(exc).__name__}: {one_line(exc)}", file=sys.stderr)
            return 1


def _error(message: object, silence: bool = False) -> int:
    """Print ``kinengine: error: <message on one line>`` to stderr; exit status 2."""
    if silence:
        _silence_stdout()
    print(f"kinengine: error: {one_line(message)}", file=sys.stderr)
    return 2


def _silence_stdout() -> None:
    """Point stdout at /dev/null, so that the flush at exit cannot fail a second time."""
    with contextlib.suppress(OSError, ValueError):
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
