"""Entry points that turn a robot name, a URDF file or URDF text into a :class:`Robot`.

Every path goes through kinengine's own strict parser and validator first
(:mod:`kinengine.urdf`); Pinocchio only ever parses the canonical XML regenerated
from the validated description.
"""

from __future__ import annotations

import os
from pathlib import Path

from .model import available_robots, catalog_entry
from .errors import URDFError
from .robot import Robot
from .urdf import LIMITS, Limits, RobotDescription, parse_urdf, read_urdf_file


def load(target: str | os.PathLike[str], *, end_effector: str | None = None,
         limits: Limits = LIMITS) -> Robot:
    """A robot by short name (see :func:`available_robots`) or by path to a .urdf file.

    ``limits``: the size limits the file must respect (:class:`kinengine.urdf.Limits`; pass a bigger
    one to load a bigger model, e.g. ``Limits(max_movable_joints=256)``).
    """
    if not isinstance(target, (str, os.PathLike)):
        raise URDFError(f"load() takes a robot name or a path to a .urdf file, got {type(target).__name__}")
    text_target = os.fspath(target)
    if isinstance(target, str) and text_target in available_robots():
        entry = catalog_entry(text_target)
        description, text = _read(entry.path, limits)
        return Robot(description, text, name=entry.name, end_effector=end_effector or entry.end_effector)
    path = Path(text_target)
    if not isinstance(target, os.PathLike) and path.suffix.lower() != ".urdf" and not path.exists():
        catalog_entry(text_target)  # raises: unknown robot, listing the names
    description, text = _read(path, limits)
    return Robot(description, text, end_effector=end_effector)


def load_urdf_string(text: str | bytes, *, end_effector: str | None = None, source: str = "<string>",
                     limits: Limits = LIMITS) -> Robot:
    """A robot from URDF XML held in memory (e.g. a ROS robot_description); ``limits`` as in :func:`load`."""
    if not isinstance(text, (str, bytes)):
        raise URDFError(f"load_urdf_string() takes URDF text (str or bytes), got {type(text).__name__}")
    description = parse_urdf(text, source=source, limits=limits)
    if isinstance(text, bytes):
        text = text.decode("utf-8", errors="replace")
    return Robot(description, text, end_effector=end_effector)


def _read(path: Path, limits: Limits) -> tuple["RobotDescription", str]:
    description = read_urdf_file(path, limits=limits)
    return description, Path(path).read_text(encoding="utf-8", errors="replace")
