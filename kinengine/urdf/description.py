"""A validated, immutable description of a URDF kinematic tree.

This is what :func:`kinengine.urdf.parse_urdf` returns after the safe XML
parse and the structural validation succeeded. Units: metres, radians.
Only kinematics (and inertials) survive; meshes, transmissions and plugins
are dropped. :meth:`RobotDescription.to_xml` regenerates a minimal URDF from
it: that text, and only that text, is what Pinocchio's C++ parser ever sees.
"""

from __future__ import annotations

from dataclasses import dataclass, field

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
        """A minimal, canonical URDF of this description (what Pinocchio parses)."""
        out = [f"<robot name={quoteattr(self.name)}>"]
        for link in self.links:
            out.append(f"  <link name={quoteattr(link.name)}>")
            if link.inertial is not None:
                i = link.inertial
                ixx, ixy, ixz, iyy, iyz, izz = (repr(float(v)) for v in i.inertia)
                out.append(
                    f'    <inertial><origin xyz="{_v(i.xyz)}" rpy="{_v(i.rpy)}"/>'
                    f'<mass value="{float(i.mass)!r}"/>'
                    f'<inertia ixx="{ixx}" ixy="{ixy}" ixz="{ixz}" iyy="{iyy}" '
                    f'iyz="{iyz}" izz="{izz}"/></inertial>'
                )
            out.append("  </link>")
        for j in self.joints:
            out.append(f'  <joint name={quoteattr(j.name)} type="{j.type}">')
            out.append(f"    <parent link={quoteattr(j.parent)}/><child link={quoteattr(j.child)}/>")
            out.append(f'    <origin xyz="{_v(j.xyz)}" rpy="{_v(j.rpy)}"/>')
            if j.movable:
                out.append(f'    <axis xyz="{_v(j.axis)}"/>')
                lim = [f'effort="{float(j.effort or 0.0)!r}"', f'velocity="{float(j.velocity or 0.0)!r}"']
                if j.lower is not None and j.upper is not None:
                    lim += [f'lower="{float(j.lower)!r}"', f'upper="{float(j.upper)!r}"']
                out.append(f"    <limit {' '.join(lim)}/>")
            if j.mimic is not None:
                m = j.mimic
                out.append(
                    f"    <mimic joint={quoteattr(m.joint)} "
                    f'multiplier="{float(m.multiplier)!r}" offset="{float(m.offset)!r}"/>'
                )
            out.append("  </joint>")
        out.append("</robot>")
        return "\n".join(out) + "\n"


def _v(v: Vector3) -> str:
    return " ".join(repr(float(x)) for x in v)


def quoteattr(value: str) -> str:
    """``value`` escaped and quoted as an XML attribute value, exactly as ``xml.sax.saxutils.quoteattr``
    does it (written out here: importing xml.sax.saxutils imports urllib.request, http, ssl and email)."""
    for raw, entity in _ATTRIBUTE_ENTITIES:
        value = value.replace(raw, entity)
    if '"' not in value:
        return f'"{value}"'
    if "'" not in value:
        return f"'{value}'"
    return '"' + value.replace('"', "&quot;") + '"'


# In this order: "&" first, so that the other entities are not escaped twice.
_ATTRIBUTE_ENTITIES = (
    ("&", "&amp;"),
    (">", "&gt;"),
    ("<", "&lt;"),
    ("\n", "&#10;"),
    ("\r", "&#13;"),
    ("\t", "&#9;"),
)
