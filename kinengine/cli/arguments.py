"""argparse value types shared by the sub-commands: bad values stop before any work is done.

Numbers are read strictly: ASCII only, Python's float literal grammar without underscores
(``1.5``, ``-2e-3``, ``.5``), whole numbers as ASCII digits; ``"1 5"``, ``"1_0"``, ``"١"`` and empty
entries are refused. Output paths are checked before the work (a folder, a missing or read-only
folder, a read-only file, a dangling link, a device other than /dev/null). :class:`OneLineParser`
prints argparse's own errors as one line (exit status 2), like every other kinengine error.

Also the robot options every robot-taking command shares (:func:`robot_command`, :func:`add_robot_arguments`,
:func:`load_robot`): ``--xacro-arg NAME=VALUE`` and ``--package NAME=PATH``, both repeatable, and
``--root BODY`` for an MJCF file; and the options several commands share (``--q``, ``--frame``, ``--frames``).
"""

from __future__ import annotations

import argparse
import os
import re
import stat
import sys
from collections.abc import Callable
from pathlib import Path
from typing import NoReturn

from ..loading import load
from ..robot import Robot

_FLOAT = re.compile(
    r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|inf|infinity|nan)", re.ASCII | re.IGNORECASE
)
_WHOLE = re.compile(r"[+-]?[0-9]+", re.ASCII)
_SPACE = " \t"


def strict_float(text: str) -> float:
    """'1.5' -> 1.5: one float literal (ASCII, no underscores or inner spaces); argparse type."""
    stripped = text.strip(_SPACE)
    if not _FLOAT.fullmatch(stripped):
        raise argparse.ArgumentTypeError(f"expected a number such as 0.5 or -1e-3, got {printable(text)!r}")
    return float(stripped)


def parse_vector(text: str) -> list[float]:
    """'0.1,-0.3,0.2' -> [0.1, -0.3, 0.2] (argparse type for --q): comma-separated float literals, spaces
    around commas allowed; empty entries, spaces inside a number, underscores and non-ASCII digits refused."""
    values = []
    for i, entry in enumerate(text.split(",")):
        stripped = entry.strip(_SPACE)
        if not _FLOAT.fullmatch(stripped):
            what = "an empty entry" if not stripped else f"{printable(stripped)!r}"
            raise argparse.ArgumentTypeError(
                f"expected comma-separated numbers such as 0.1,-0.3,2e-3; entry {i + 1} is {what}"
            )
        values.append(float(stripped))
    return values


def whole_number(text: str, low: int, high: int) -> int:
    """An ASCII whole number in [low, high] (ArgumentTypeError otherwise)."""
    stripped = text.strip(_SPACE)
    if not _WHOLE.fullmatch(stripped):
        raise argparse.ArgumentTypeError(f"expected a whole number, got {printable(text)!r}")
    value = int(stripped)
    if not low <= value <= high:
        raise argparse.ArgumentTypeError(f"expected a whole number in [{low}, {high}], got {value}")
    return value


def positive_int(text: str) -> int:
    """'20' -> 20; zero, negatives and non-integers are refused (argparse type for counts)."""
    return whole_number(text, 1, 2**63 - 1)


def bounded_int(low: int, high: int) -> Callable[[str], int]:
    """An argparse type for a whole number in [low, high]."""

    def parse(text: str) -> int:
        return whole_number(text, low, high)

    parse.__name__ = "whole number"
    return parse


def name_argument(text: str) -> str:
    """A non-empty name (argparse type for --frame and the like)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a name, got an empty string")
    return text


def output_path(text: str) -> Path:
    """A file kinengine may write (argparse type for --json, --plot, -o), checked before any work: not
    empty, not a folder, its folder exists and is writable, not a dangling link, not a read-only file,
    not a device (but /dev/null)."""
    if not text:
        raise argparse.ArgumentTypeError("expected a file name, got an empty string")
    path = Path(text)
    shown = printable(text)
    folder = path.parent if str(path.parent) else Path(".")
    try:
        if path.is_symlink() and not path.exists():
            raise argparse.ArgumentTypeError(f"{shown!r} is a link to a missing file; give a plain file name")
        if path.is_dir():
            raise argparse.ArgumentTypeError(
                f"{shown!r} is a folder; give a file name, e.g. {shown.rstrip('/')}/out"
            )
        if not folder.is_dir():
            raise argparse.ArgumentTypeError(
                f"cannot write {shown!r}: folder {printable(str(folder))!r} does not exist"
            )
        if not os.access(folder, os.W_OK | os.X_OK):
            raise argparse.ArgumentTypeError(
                f"cannot write {shown!r}: folder {printable(str(folder))!r} is not writable"
            )
        if path.exists():
            mode = path.stat().st_mode
            if not stat.S_ISREG(mode) and os.path.realpath(path) != os.devnull:
                raise argparse.ArgumentTypeError(
                    f"cannot write {shown!r}: not a regular file (a device, FIFO or socket)"
                )
            if not os.access(path, os.W_OK) or not mode & (stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH):
                # the mode bits too: root could write a file marked read-only, but should not overwrite it
                raise argparse.ArgumentTypeError(f"cannot write {shown!r}: the file is read-only")
    except OSError as exc:  # a name too long, a loop of links, no permission to look
        raise argparse.ArgumentTypeError(f"cannot write {shown!r}: {exc.strerror}") from None
    return path


_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def printable(text: str) -> str:
    """``text`` with control characters (newlines, tabs, escapes) as \\xNN / \\uNNNN: a name from a file
    can never break a line of output or move the terminal's cursor."""
    return _CONTROL.sub(
        lambda m: f"\\x{ord(m.group()):02x}" if ord(m.group()) < 0x100 else f"\\u{ord(m.group()):04x}", text
    )


def one_line(message: object) -> str:
    """An error message on one line: line breaks (e.g. in libxml2's messages) become spaces, other control
    characters are escaped (:func:`printable`)."""
    return printable(re.sub(r"\s*[\r\n\u2028\u2029]+\s*", " ", str(message)).strip())


class OneLineParser(argparse.ArgumentParser):
    """argparse with its errors as one line on stderr (``kinengine: error: ...``, exit status 2), not usage
    plus error; sub-command parsers made from it inherit the behaviour."""

    def error(self, message: str) -> NoReturn:
        hint = f" (see {self.prog} --help)"
        print(f"kinengine: error: {one_line(self.prog + ': ' + message)}{hint}", file=sys.stderr)
        raise SystemExit(2)


def name_value(text: str) -> tuple[str, str]:
    """'ur_type=ur5e' -> ('ur_type', 'ur5e') (argparse type for --xacro-arg and --package)."""
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, e.g. ur_type=ur5e, got {text!r}")
    return name.strip(), value


ROBOT_HELP = "robot name or path to a .urdf, .xacro or MJCF .xml file"
"""The help text of the robot argument of every robot-taking command."""


def add_robot_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of a robot given as a .xacro file, with package:// paths (repeatable) or as MJCF."""
    parser.add_argument(
        "--xacro-arg",
        dest="xacro_args",
        type=name_value,
        action="append",
        default=None,
        metavar="NAME=VALUE",
        help="argument of a .xacro robot file, e.g. ur_type=ur5e (repeatable)",
    )
    parser.add_argument(
        "--package",
        dest="packages",
        type=name_value,
        action="append",
        default=None,
        metavar="NAME=PATH",
        help="folder of ROS package NAME for $(find NAME) and "
        "package://NAME/... (repeatable; default: ROS_PACKAGE_PATH, then the file's folders)",
    )
    parser.add_argument(
        "--root",
        default=None,
        metavar="BODY",
        help="of an MJCF (.xml) file: the top body of the tree to load (default: the first child of the "
        "world body)",
    )
    parser.add_argument(
        "--trust-xacro",
        action="store_true",
        help="evaluate a .xacro file's expressions with xacro's own Python eval, which can run any "
        "command (default: kinengine's restricted evaluator); only for files you would build with ROS",
    )


def robot_command(
    subparsers: argparse._SubParsersAction,
    name: str,
    help: str,
    *,
    description: str | None = None,
    **argument: str,
) -> argparse.ArgumentParser:
    """The parser of a sub-command that takes a robot: the positional ``robot`` (a name or file;
    ``argument``: e.g. its ``metavar`` or ``nargs``), then the options of :func:`add_robot_arguments`."""
    parser = subparsers.add_parser(name, help=help, description=description)
    parser.add_argument("robot", help=ROBOT_HELP, **argument)
    add_robot_arguments(parser)
    return parser


Q_HELP = "comma-separated joint values [rad | m] (default: zero clipped into the limits)"
FRAMES_HELP = "comma-separated frames drawn as RGB triads (default: the end effector; '' for none)"


def add_q_argument(parser: argparse.ArgumentParser) -> None:
    """``--q v1,v2,...``: the configuration [rad | m] (None when not given: the command's default q)."""
    parser.add_argument("--q", type=parse_vector, default=None, help=Q_HELP)


def add_frame_argument(
    parser: argparse.ArgumentParser, help: str = "frame name (default: the end effector)"
) -> None:
    """``--frame NAME``: one frame (None when not given: the end effector)."""
    parser.add_argument("--frame", type=name_argument, default=None, help=help)


def name_list(text: str) -> list[str]:
    """'tool0, flange' -> ['tool0', 'flange'] (argparse type for --frames)."""
    return [name for name in text.replace(" ", "").split(",") if name]


def add_frames_argument(parser: argparse.ArgumentParser) -> None:
    """``--frames a,b``: frames drawn as triads (None when not given: the end effector; '' for none)."""
    parser.add_argument("--frames", type=name_list, default=None, help=FRAMES_HELP)


def load_robot(args: argparse.Namespace, target: str | None = None) -> Robot:
    """The Robot named by ``target`` (default ``args.robot``) with the options of
    :func:`add_robot_arguments`."""
    return load(
        args.robot if target is None else target,
        xacro_args=None if args.xacro_args is None else dict(args.xacro_args),
        packages=None if args.packages is None else dict(args.packages),
        root=args.root,
        trust_xacro=bool(getattr(args, "trust_xacro", False)),
    )


def summary(doc: str | None) -> str:
    """A module docstring's first paragraph on one line, without reST markup, for --help."""
    return " ".join(doc.split("\n\n")[0].split()).replace("``", "") if doc else ""


_PENDING: list[str] = []  # warnings of the running command, printed when it succeeds (flush_warnings)


def defer_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: object = None,
    line: str | None = None,
) -> None:
    """``warnings.showwarning`` of the command line: keep the warning as one line until the command ends,
    so that a command that fails prints its one error line only (a library's warning about the same
    input, e.g. a gimbal lock, would otherwise come first)."""
    _PENDING.append(f"kinengine: warning: {one_line(message)}")


def flush_warnings() -> None:
    """Print the warnings kept so far (each once) on stderr; a long-running command calls it first."""
    for text in dict.fromkeys(_PENDING):
        print(text, file=sys.stderr)
    _PENDING.clear()


def drop_warnings() -> None:
    """Forget the warnings kept so far (the command failed: its error line says what went wrong)."""
    _PENDING.clear()
