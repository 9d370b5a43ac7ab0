"""argparse value types shared by the sub-commands: bad values stop before any work is done.

Also the robot options every robot-taking command shares (:func:`add_robot_arguments`,
:func:`load_robot`): ``--xacro-arg NAME=VALUE`` and ``--package NAME=PATH``, both repeatable.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from ..loading import load
from ..robot import Robot


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


def name_value(text: str) -> tuple[str, str]:
    """'ur_type=ur5e' -> ('ur_type', 'ur5e') (argparse type for --xacro-arg and --package)."""
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, e.g. ur_type=ur5e, got {text!r}")
    return name.strip(), value


def add_robot_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of a robot given as a .xacro file or with package:// paths (repeatable)."""
    parser.add_argument("--xacro-arg", dest="xacro_args", type=name_value, action="append", default=None,
                        metavar="NAME=VALUE", help="argument of a .xacro robot file, e.g. ur_type=ur5e "
                        "(repeatable)")
    parser.add_argument("--package", dest="packages", type=name_value, action="append", default=None,
                        metavar="NAME=PATH", help="folder of ROS package NAME for $(find NAME) and "
                        "package://NAME/... (repeatable; default: ROS_PACKAGE_PATH, then the file's folders)")


def load_robot(args: argparse.Namespace, target: str | None = None) -> Robot:
    """The Robot named by ``target`` (default ``args.robot``) with the options of :func:`add_robot_arguments`."""
    return load(args.robot if target is None else target,
                xacro_args=None if args.xacro_args is None else dict(args.xacro_args),
                packages=None if args.packages is None else dict(args.packages))


def summary(doc: str | None) -> str:
    """A module docstring's first line without reST markup, for --help."""
    return doc.splitlines()[0].replace("``", "") if doc else ""
