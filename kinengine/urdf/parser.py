"""The entry points: URDF text or file in, validated :class:`RobotDescription` out.

Stages, each refusing with a :class:`~kinengine.errors.URDFError` that names
the source, element and line: the safe XML parse (:mod:`.safe_xml`), the model
size limits (counted on the raw elements), the elements (:mod:`.elements`),
the tree (:mod:`.tree`). Pinocchio never parses the input itself, only
:meth:`RobotDescription.to_xml` of the result.
"""

from __future__ import annotations

import os
import warnings

from lxml import etree

from ..errors import URDFError
from .description import RobotDescription
from .elements import Where, read_joint, read_link, read_name
from .limits import LIMITS, Limits
from .magnitudes import check_magnitudes
from .safe_xml import parse_xml
from .source import read_bytes_once
from .tree import assemble


def parse_urdf(
    document: str | bytes, source: str = "<string>", *, limits: Limits = LIMITS
) -> RobotDescription:
    """The validated description of URDF ``document`` (str or bytes); URDFError otherwise.

    Each non-unit joint axis is normalized with a ``UserWarning`` (also kept in
    ``RobotDescription.warnings``), as is each ``<mimic>`` ignored on a fixed joint.
    """
    if not isinstance(limits, Limits):
        raise URDFError(f"limits= takes a kinengine.urdf.Limits, got {type(limits).__name__}", source=source)
    root = parse_xml(document, source=source, limits=limits)
    if root.tag != "robot":
        raise URDFError(
            f"the root element is <{root.tag}>, expected <robot>", source=source, line=root.sourceline
        )
    name = read_name(root, "name", Where(source, "robot"), limits)
    _refuse_xacro(root, source)
    link_elements, joint_elements = root.findall("link"), root.findall("joint")
    movable = int(root.xpath("count(joint[not(@type='fixed')])"))
    for count, limit, what in (
        (len(link_elements), limits.max_links, "links"),
        (len(joint_elements), limits.max_joints, "joints"),
        (movable, limits.max_movable_joints, "movable_joints"),
    ):
        if count > limit:
            raise URDFError(
                f"the robot has {count} {what.replace('_', ' ')}, more than Limits.max_{what} = "
                f"{limit}; pass parse_urdf(..., limits=Limits(max_{what}=...)) to allow more",
                source=source,
                element=f"robot {name!r}",
            )
    found: list[str] = []
    links = [read_link(e, source, limits, found) for e in link_elements]
    joints = [read_joint(e, source, limits, found) for e in joint_elements]
    check_magnitudes(links, joints, source=source, limits=limits)
    description = assemble(name, links, joints, source=source, warnings=found, limits=limits)
    for message in found:
        warnings.warn(f"{source}: {message}", UserWarning, stacklevel=2)
    return description


def read_urdf_file(path: str | os.PathLike[str], *, limits: Limits = LIMITS) -> RobotDescription:
    """The validated description of the URDF file at ``path``; URDFError naming the path otherwise
    (the file is read once: :func:`.source.read_bytes_once`)."""
    source, data = read_bytes_once(path, limits)
    return parse_urdf(data, source=source, limits=limits)


def _refuse_xacro(root: etree._Element, source: str) -> None:
    macros = root.xpath("*[contains(namespace-uri(), 'xacro')]")
    if macros:
        tag = f"{macros[0].prefix}:{etree.QName(macros[0]).localname}"
        raise URDFError(
            f"<{tag}> is a xacro macro: expand the file first (xacro robot.urdf.xacro > robot.urdf)",
            source=source,
            line=macros[0].sourceline,
        )
