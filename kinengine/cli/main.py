"""The kinengine command line: list, info, pose, ik, verify, bench, show, view, reach, place and
collision-pairs (one module per command).

Every sub-command handler takes the parsed arguments and returns an exit code. Every bad input
ends in one line on stderr, ``kinengine: error: ...``, and exit status 2: argparse's own errors
(:class:`~kinengine.cli.arguments.OneLineParser`), kinengine errors, an output that cannot be
written (a full disk, /dev/full as stdout) and memory that runs out. Names are printed with their
control characters escaped; stdout and stderr escape what their encoding cannot show
(``PYTHONIOENCODING=ascii``). An unexpected exception is one line too, with exit status 1. Warnings
are kept until the command ends: printed (one line each) when it succeeds, dropped when it fails, so
that a failing command prints its error line alone. A closed stdout is one error line, exit status 2.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import sys
import warnings
from collections.abc import Sequence

from .. import KinematicsError, __version__, accelerator_status
from . import bench, catalog, collisions, ik, info, pose, reach, show, verify, view
from .arguments import OneLineParser, defer_warning, drop_warnings, flush_warnings, one_line, summary


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="kinengine", description=summary(__doc__))
    parser.add_argument(
        "--version",
        action=_Version,
        nargs=0,
        help="the version and whether the C accelerator is on, then exit",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    for command in (catalog, info, pose, ik, verify, bench, show, view, reach, collisions):
        command.add_parser(sub)
    return parser


class _Version(argparse.Action):
    """--version: two lines as written (argparse's own version action would re-wrap them into one)."""

    def __call__(self, parser: argparse.ArgumentParser, *args: object) -> None:
        print(f"kinengine {__version__}\n{accelerator_status()}")
        parser.exit()


_VALUE_OPTIONS = ("--q", "--view", "--xyz", "--rpy", "--near")
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


def main(argv: Sequence[str] | None = None) -> int:
    for stream in (sys.stdout, sys.stderr):  # e.g. PYTHONIOENCODING=ascii and a robot named "bras_é"
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    if sys.stdout is None:  # started with stdout closed (`kinengine list >&-`)
        if sys.stderr is not None:
            print("kinengine: error: standard output is closed; run with an open stdout", file=sys.stderr)
        return 2
    args = build_parser().parse_args(join_negative_values(sys.argv[1:] if argv is None else argv))
    with warnings.catch_warnings():
        warnings.showwarning = defer_warning
        try:
            code = int(args.handler(args))
            sys.stdout.flush()  # a full disk or /dev/full as stdout fails here, not at exit
            flush_warnings()
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
            drop_warnings()
            print(f"kinengine: internal error: {type(exc).__name__}: {one_line(exc)}", file=sys.stderr)
            return 1


def _error(message: object, silence: bool = False) -> int:
    """Print ``kinengine: error: <message on one line>`` to stderr (the command's warnings dropped);
    exit status 2."""
    drop_warnings()
    if silence:
        _silence_stdout()
    print(f"kinengine: error: {one_line(message)}", file=sys.stderr)
    return 2


def _silence_stdout() -> None:
    """Point stdout at /dev/null, so that the flush at exit cannot fail a second time."""
    with contextlib.suppress(OSError, ValueError):
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
