"""A validated, immutable description of a URDF kinematic tree.

This is what :func:`kinengine.urdf.parse_urdf` returns after the safe XML
parse and the structural validation succeeded. Units: metres, radians.
Only kinematics (and inertials) survive; meshes, transmissions and plugins
are dropped. :meth:`RobotDescription.to_xml` regenerates a minimal URDF from
it: that text, and only that text, is what Pinocchio's C++ parser ever sees.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lxml import etree

Vector3 = tuple[float, float, float]

MOVABLE_TYPES = ("revolute", "continuous", "prismatic")
SUPPORTED_TYPES = MOVABLE_TYPES + ("fixed",)


@dataclass(frozen=True)
class Inertial:
    """Mass [kg], centre of mass and inertia (ixx, ixy, ixz, iyy, iyz, izz) [kg m^2] in the link frame."""

    mass: float
    xyz: Vector3 = (0.0, 0.0, 0.0)
    rpy: Vector3 = (0.0, 0.0, 0.0)
    inertia: tuple[float, float, float, float, float, float] = (0.0,) * 6


@dataclass(frozen=True)
class Link:
    name: str
    inertial: Inertial | None = None
    line: int | None = None


@dataclass(frozen=True)
class Mimic:
    """q_this = multiplier * q_joint + offset."""

    joint: str
    multiplier: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class Joint:
    """A URDF joint. ``axis`` is a unit vector in the joint frame (normalized on parse).

    ``lower``/``upper`` are None for continuous and fixed joints; ``velocity``
    and ``effort`` are None where the file gives none.
    """

    name: str
    type: str
    parent: str
    child: str
    xyz: Vector3 = (0.0, 0.0, 0.0)
    rpy: Vector3 = (0.0, 0.0, 0.0)
    axis: Vector3 = (1.0, 0.0, 0.0)
    lower: float | None = None
    upper: float | None = None
    velocity: float | None = None
    effort: float | None = None
    mimic: Mimic | None = None
    line: int | None = None

    @property
    def movable(self) -> bool:
        return self.type in MOVABLE_TYPES


@dataclass(frozen=True)
class RobotDescription:
    """A validated tree: exactly one root, every link reached once, no cycles.

    ``joints`` is in depth-first order from the root, sibling joints sorted by name:
    the order urdfdom, and so Pinocchio, builds its joints in.
    """

    name: str
    root: str
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    source: str = "<string>"
    warnings: tuple[str, ...] = field(default=())

    def joint(self, name: str) -> Joint:
        for j in self.joints:
            if j.name == name:
                return j
        raise KeyError(name)

    @property
    def movable_joints(self) -> tuple[Joint, ...]:
        """Movable joints that own a coordinate (mimic joints excluded), in tree order."""
        return tuple(j for j in self.joints if j.movable and j.mimic is None)

    def to_xml(self) -> str:
        """A minimal, canonical URDF of this description (what Pinocchio parses), serialized by lxml (which
        escapes and quotes every attribute value)."""
        robot = etree.Element("robot", name=self.name)
        robot.text = "\n  "
        for link in self.links:
            element = etree.SubElement(robot, "link", name=link.name)
            if link.inertial is not None:
                i = link.inertial
                inertial = etree.SubElement(element, "inertial")
                etree.SubElement(inertial, "origin", xyz=_v(i.xyz), rpy=_v(i.rpy))
                etree.SubElement(inertial, "mass", value=repr(float(i.mass)))
                names = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
                etree.SubElement(
                    inertial, "inertia", {n: repr(float(v)) for n, v in zip(names, i.inertia, strict=True)}
                )
            element.tail = "\n  "
        for j in self.joints:
            element = etree.SubElement(robot, "joint", name=j.name, type=j.type)
            etree.SubElement(element, "parent", link=j.parent)
            etree.SubElement(element, "child", link=j.child)
            etree.SubElement(element, "origin", xyz=_v(j.xyz), rpy=_v(j.rpy))
            if j.movable:
                etree.SubElement(element, "axis", xyz=_v(j.axis))
                limit = {"effort": repr(float(j.effort or 0.0)), "velocity": repr(float(j.velocity or 0.0))}
                if j.lower is not None and j.upper is not None:
                    limit.update(lower=repr(float(j.lower)), upper=repr(float(j.upper)))
                etree.SubElement(element, "limit", limit)
            if j.mimic is not None:
                m = j.mimic
                mimic = {
                    "joint": m.joint,
                    "multiplier": repr(float(m.multiplier)),
                    "offset": repr(float(m.offset)),
                }
                etree.SubElement(element, "mimic", mimic)
            element.tail = "\n  "
        if len(robot):
            robot[-1].tail = "\n"
        return etree.tostring(robot, encoding="unicode") + "\n"


def _v(v: Vector3) -> str:
    return " ".join(repr(float(x)) for x in v)
