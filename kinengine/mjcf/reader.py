"""The MJCF entry point: a file in, kinengine's description and an equivalent kinematic URDF out.

The URDF is :meth:`RobotDescription.to_xml` of the description with each body's geoms as ``<visual>``
(drawn by the viewer) and ``<collision>`` (checked by the collision queries) elements of its link
(:mod:`.geoms`); kinematics readers ignore them.
"""

from __future__ import annotations

import os
from pathlib import Path

from lxml import etree

from ..urdf.description import RobotDescription
from ..urdf.limits import LIMITS, Limits
from .compiler import compile_mjcf
from .convert import MJCFNames, describe
from .geoms import geom_elements


def read_mjcf_file(
    path: str | os.PathLike[str], *, root: str | None = None, limits: Limits = LIMITS
) -> tuple[RobotDescription, str]:
    """(description, URDF text) of the MJCF file at ``path``: the kinematic tree whose top body is
    ``root`` (default: the first child of the world body), rooted at MuJoCo's world frame (link
    ``world``). MJCFError naming the file for anything MuJoCo or kinengine refuses."""
    source, model, meshdir = compile_mjcf(path, limits=limits)
    description = describe(model, source, root=root, limits=limits)
    names = MJCFNames(model, source, limits)
    links = {link.name for link in description.links}
    bodies = {b: names.body[b] for b in range(model.nbody) if names.body[b] in links}
    geoms = geom_elements(model, bodies, Path(source).parent, meshdir, source)
    document = etree.fromstring(description.to_xml())
    for element in document.iter("link"):
        for geom in geoms.get(element.get("name", ""), ()):
            element.append(etree.fromstring(geom))
    return description, etree.tostring(document, encoding="unicode") + "\n"


__all__ = ["read_mjcf_file"]
