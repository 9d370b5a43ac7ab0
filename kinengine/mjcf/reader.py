"""The MJCF entry point: a file in, kinengine's description and an equivalent kinematic URDF out."""

from __future__ import annotations

import os

from ..urdf.description import RobotDescription
from ..urdf.limits import LIMITS, Limits
from .compiler import compile_mjcf
from .convert import describe


def read_mjcf_file(
    path: str | os.PathLike[str], *, root: str | None = None, limits: Limits = LIMITS
) -> tuple[RobotDescription, str]:
    """(description, URDF text) of the MJCF file at ``path``: the kinematic tree whose top body is
    ``root`` (default: the first child of the world body), rooted at MuJoCo's world frame (link
    ``world``). MJCFError naming the file for anything MuJoCo or kinengine refuses."""
    source, model = compile_mjcf(path, limits=limits)
    description = describe(model, source, root=root, limits=limits)
    return description, description.to_xml()


__all__ = ["read_mjcf_file"]
