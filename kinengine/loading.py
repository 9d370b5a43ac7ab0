"""Entry points that turn a robot name, a URDF, xacro or MJCF file or URDF text into a :class:`Robot`.

Every path goes through kinengine's own strict parser and validator first
(:mod:`kinengine.urdf`); Pinocchio only ever parses the canonical XML regenerated
from the validated description. A .xacro file is expanded in-process first
(:func:`kinengine.urdf.xacro.expand_xacro`, no ROS needed). Each load issues at most one
warning: what the parser corrected or ignored (all of it in ``description.warnings``) and,
for a floating-base robot, that its root link is held fixed
(:func:`kinengine.model.floating_base.floating_base_note`). An MJCF (MuJoCo XML) file is compiled by
MuJoCo and converted by :mod:`kinengine.mjcf` (extra ``[mjcf]``).
"""

from __future__ import annotations

import os
import threading
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TypeVar

from .errors import OptionError, URDFError
from .mjcf import is_mjcf
from .model import catalog_entry, find_entry
from .model.floating_base import floating_base_note
from .robot import Robot
from .urdf import LIMITS, Limits, RobotDescription, parse_urdf
from .urdf.source import decode_xml, read_bytes_once

_WARNINGS_LOCK = threading.Lock()  # catch_warnings swaps process-wide state: two loads must not interleave it


_T = TypeVar("_T")


def load(
    target: str | os.PathLike[str],
    *,
    end_effector: str | None = None,
    limits: Limits = LIMITS,
    xacro_args: Mapping[str, str | float | int] | None = None,
    packages: Mapping[str, str | os.PathLike[str]] | None = None,
    root: str | None = None,
    trust_xacro: bool = False,
) -> Robot:
    """A robot by short name (see :func:`available_robots`) or by path to a .urdf, .xacro or MJCF .xml file.

    ``limits``: the size limits the file must respect (:class:`kinengine.urdf.Limits`; pass a bigger
    one to load a bigger model, e.g. ``Limits(max_movable_joints=256)``).
    ``xacro_args``: xacro arguments (name -> value) of a .xacro / .urdf.xacro file, which is expanded
    in-process (no ROS needed) and then parsed as strictly as a URDF.
    ``packages``: ROS package name -> folder, for ``$(find pkg)`` and ``package://`` URIs; packages not
    named are looked up in ``ROS_PACKAGE_PATH``, then in the folders above the file. Kept on the robot
    as ``robot.packages`` (meshes are resolved with it).
    ``root``: for an MJCF file (a ``<mujoco>`` model, compiled by MuJoCo: ``pip install 'kinengine[mjcf]'``),
    the top body (a child of the world body) of the tree to load; default: the first one. Poses are in
    MuJoCo's world frame, link ``world``; see docs/loading.md.
    ``trust_xacro``: a .xacro file's expressions are evaluated by kinengine's restricted evaluator
    (:mod:`kinengine.urdf.xacro_eval`) unless this is True, which runs xacro's own Python ``eval``:
    only for files you would also build with ROS (it can run any command).
    """
    if not isinstance(target, (str, os.PathLike)):
        raise URDFError(f"load() takes a robot name or a path to a .urdf file, got {type(target).__name__}")
    _check_limits(limits)
    text_target = os.fspath(target)
    packages = _packages(packages, text_target)
    is_xacro = text_target.lower().endswith(".xacro")
    if xacro_args is not None and not is_xacro:
        raise URDFError(f"xacro_args= is for .xacro files; {text_target!r} is not one (drop xacro_args=)")
    entry = find_entry(text_target) if isinstance(target, str) else None
    if entry is None and is_mjcf(text_target):
        from .mjcf.reader import read_mjcf_file  # here: numpy's model editing is imported for MJCF only

        description, text = _warn_once(lambda: read_mjcf_file(text_target, root=root, limits=limits))
        return Robot(description, text, end_effector=end_effector, packages=packages)
    if root is not None:
        raise URDFError(f"root= is for MJCF (.xml) files; {text_target!r} is not one (drop root=)")
    if entry is not None:
        description, text = _warn_once(lambda: _read(entry.path, limits))
        robot = Robot(
            description,
            text,
            name=entry.name,
            end_effector=entry.end_effector if end_effector is None else end_effector,
            packages=packages,
        )
        return robot.locked(dict(entry.locked)) if entry.locked else robot
    path = Path(text_target)
    if (
        not isinstance(target, os.PathLike)
        and path.suffix.lower() not in (".urdf", ".xacro", ".xml")
        and not _exists(path)
    ):
        catalog_entry(text_target)  # raises: unknown robot, listing the names
    if is_xacro:
        # values as text, exactly as expand_xacro itself turns them (xacro:arg values are strings)
        as_text = (
            {k: str(v) for k, v in xacro_args.items()} if isinstance(xacro_args, Mapping) else xacro_args
        )
        from .urdf.xacro import expand_xacro  # here: xacro and xml.dom are imported for .xacro files only

        text = expand_xacro(path, args=as_text, packages=packages, limits=limits, trust_xacro=trust_xacro)
        description, _ = _warn_once(lambda: (parse_urdf(text, source=text_target, limits=limits), None))
    else:
        description, text = _warn_once(lambda: _read(path, limits))
    return Robot(description, text, end_effector=end_effector, packages=packages)


def load_urdf_string(
    text: str | bytes,
    *,
    end_effector: str | None = None,
    source: str = "<string>",
    limits: Limits = LIMITS,
    packages: Mapping[str, str | os.PathLike[str]] | None = None,
) -> Robot:
    """A robot from URDF XML held in memory (e.g. a ROS robot_description); ``limits`` and ``packages``
    as in :func:`load`."""
    if not isinstance(text, (str, bytes)):
        raise URDFError(f"load_urdf_string() takes URDF text (str or bytes), got {type(text).__name__}")
    _check_limits(limits)
    packages = _packages(packages, source)
    description, _ = _warn_once(lambda: (parse_urdf(text, source=source, limits=limits), None))
    if isinstance(text, bytes):
        text = decode_xml(text)
    return Robot(description, text, end_effector=end_effector, packages=packages)


def extra_coordinates(name: str) -> tuple[str, ...]:
    """The coordinates of catalog robot ``name`` that move a gripper rather than the arm (e.g. the Panda's
    ``panda_finger_joint1``); lock them with ``robot.locked({joint: value})``. Empty for other robots."""
    entry = find_entry(name)
    return entry.extra_coordinates if entry is not None else ()


def _packages(packages: object, source: str) -> dict[str, str]:
    """``packages=`` checked: a mapping of package name (str) to folder (str or path), as plain strings."""
    if packages is None:
        return {}
    if not isinstance(packages, Mapping) or not all(
        isinstance(k, str) and k and isinstance(v, (str, os.PathLike)) for k, v in packages.items()
    ):
        raise URDFError(
            f"packages= takes a mapping of ROS package name to folder, e.g. "
            f"{{'my_robot_description': '/path/to/my_robot_description'}}, got {packages!r:.80}",
            source=source,
        )
    return {k: os.fspath(v) for k, v in packages.items()}


def _warn_once(read: Callable[[], tuple[RobotDescription, _T]]) -> tuple[RobotDescription, _T]:
    """``read()`` with the parser's warnings (one per corrected element) held back, then one warning for the
    load: the floating-base note and a summary of ``description.warnings``. Other warnings pass through."""
    with _WARNINGS_LOCK, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        description, other = read()
    notes = description.warnings
    for w in caught:
        if not any(str(w.message).endswith(note) for note in notes):
            warnings.warn(w.message, w.category, stacklevel=3)
    parts = [floating_base_note(description)]
    if notes:
        parts.append(
            notes[0]
            if len(notes) == 1
            else f"{len(notes)} notes on the description, e.g. {notes[0]} (robot.description.warnings "
            f"lists them all)"
        )
    if any(parts):
        warnings.warn(f"{description.source}: " + "; ".join(p for p in parts if p), UserWarning, stacklevel=3)
    return description, other


def _read(path: Path, limits: Limits) -> tuple[RobotDescription, str]:
    """The description and the text of one read of the file: ``urdf_text`` is exactly what was parsed,
    decoded as its XML declares (see :mod:`kinengine.urdf.source`)."""
    source, data = read_bytes_once(path, limits)
    return parse_urdf(data, source=source, limits=limits), decode_xml(data)


def _check_limits(limits: object) -> None:
    if not isinstance(limits, Limits):
        raise OptionError(
            f"limits= takes a kinengine.urdf.Limits (e.g. Limits(max_movable_joints=256)), got "
            f"{type(limits).__name__}"
        )


def _exists(path: Path) -> bool:
    """Whether ``path`` names something; False for a name the OS refuses (too long, NUL, no permission)."""
    try:
        return path.exists()
    except (OSError, ValueError):
        return False
