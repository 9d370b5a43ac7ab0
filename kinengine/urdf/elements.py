"""Reading one ``<link>`` or ``<joint>`` element into a :class:`Link` or :class:`Joint`.

Every number is a finite decimal; vectors have exactly three of them. Defaults
follow the URDF specification: origin xyz and rpy 0 0 0, axis 1 0 0, limit
lower and upper 0, mimic multiplier 1 and offset 0. The numbers of
``<calibration>``, ``<dynamics>`` and ``<safety_controller>``, and of a fixed joint's
``<axis>``, ``<limit>`` and ``<mimic>``, are checked too (urdfdom and yourdfpy refuse a
file whose numbers they cannot read) but not kept. Link and joint
names may not be "universe", Pinocchio's name for the world frame and joint 0.
A child element that URDF allows once (``<origin>``, ``<axis>``, ``<limit>``, ...) but that appears
more often is read from its first occurrence, as urdfdom and yourdfpy read it, with a warning.
Cross-element rules (names that must exist, the tree) live in :mod:`kinengine.urdf.tree`.
"""

from __future__ import annotations

import math
import re
from typing import overload

from lxml import etree

from ..errors import URDFError
from .description import MOVABLE_TYPES, SUPPORTED_TYPES, Inertial, Joint, Link, Mimic, Vector3
from .limits import Limits

_DECIMAL = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")  # ASCII, as urdfdom reads
_UNIT_TOLERANCE = 1e-9  # |‖axis‖ - 1| above this: normalize and warn; ‖axis‖ below it: refuse
_INERTIA = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
_UNUSED_NUMBERS = {
    "calibration": ("rising", "falling"),
    "dynamics": ("damping", "friction"),
    "safety_controller": ("soft_lower_limit", "soft_upper_limit", "k_position", "k_velocity"),
}
_FIXED_IGNORED = {"limit": ("lower", "upper", "effort", "velocity"), "mimic": ("multiplier", "offset")}
_RESERVED = "universe"
_FLOATING = (
    "a fixed-base model cannot have a {type} joint: kinengine models arms and trees bolted to "
    "the world. Remove the joint and its parent link (its child becomes the root) or make it fixed; "
    "a floating-base robot (legged, humanoid, flying) is then modelled with its base held still"
)


class Where:
    """Where an element sits, for error messages: ``source``, ``joint 'elbow'``, line; and the list
    that warnings about it go to (None: not kept)."""

    def __init__(self, source: str, label: str, warnings: list[str] | None = None) -> None:
        self.source, self.label, self.warnings = source, label, warnings

    def error(self, message: str, element: etree._Element) -> URDFError:
        return URDFError(message, source=self.source, element=self.label, line=element.sourceline)


def read_name(element: etree._Element, attribute: str, where: Where, limits: Limits) -> str:
    """A required, non-empty name attribute of bounded length."""
    value = element.get(attribute)
    if value is None:
        raise where.error(f"<{element.tag}> has no {attribute!r} attribute", element)
    if not value:
        raise where.error(f"<{element.tag}> has an empty {attribute!r} attribute", element)
    if len(value) > limits.max_name_length:
        raise where.error(
            f"<{element.tag} {attribute}> has {len(value)} characters, more than "
            f"Limits.max_name_length = {limits.max_name_length}",
            element,
        )
    if value == _RESERVED and element.tag in ("link", "joint"):
        raise where.error(
            f'<{element.tag} {attribute}="{_RESERVED}">: the name is reserved (Pinocchio calls '
            "its world frame and joint 0 so); rename it",
            element,
        )
    return value


def read_link(
    element: etree._Element, source: str, limits: Limits, warnings: list[str] | None = None
) -> Link:
    """A link: its name and, if present, its inertial [kg, m, rad, kg m^2]; appends to ``warnings``."""
    name = read_name(element, "name", Where(source, "link"), limits)
    where = Where(source, f"link {name!r}", warnings)
    inertial = _single(_children(element), "inertial", where)
    return Link(
        name=name, inertial=None if inertial is None else _inertial(inertial, where), line=element.sourceline
    )


def read_joint(element: etree._Element, source: str, limits: Limits, warnings: list[str]) -> Joint:
    """A joint with its origin [m, rad], unit axis, limits [rad or m] and mimic; appends to ``warnings``."""
    name = read_name(element, "name", Where(source, "joint"), limits)
    where = Where(source, f"joint {name!r}", warnings)
    kind = element.get("type")
    if kind in ("floating", "planar"):
        raise where.error(_FLOATING.format(type=kind), element)
    if kind not in SUPPORTED_TYPES:
        got = "no type attribute" if kind is None else f"unsupported type {kind!r}"
        raise where.error(f"{got}; supported types: {', '.join(SUPPORTED_TYPES)}", element)
    children = _children(element)
    links = []
    for tag in ("parent", "child"):
        link = _single(children, tag, where)
        if link is None:
            raise where.error(f"has no <{tag} link=...> element", element)
        links.append(read_name(link, "link", where, limits))
    xyz, rpy = _origin(children, where)
    fields: dict = {}
    mimic = _single(children, "mimic", where)
    if kind in MOVABLE_TYPES:
        fields["axis"] = _axis(children, where, warnings)
        fields.update(_limits(children, element, kind, where))
        if mimic is not None:
            fields["mimic"] = Mimic(
                joint=read_name(mimic, "joint", where, limits),
                multiplier=_number(mimic, "multiplier", where, 1.0),
                offset=_number(mimic, "offset", where, 0.0),
            )
    else:  # a fixed joint: <axis>, <limit> and <mimic> are ignored, but other URDF readers parse them
        axis = _single(children, "axis", where)
        if axis is not None:
            _vector(axis, "xyz", where, (1.0, 0.0, 0.0))
        for tag, attributes in _FIXED_IGNORED.items():
            extra = _single(children, tag, where)
            for attribute in attributes if extra is not None else ():
                _number(extra, attribute, where, None)
        if mimic is not None:
            read_name(mimic, "joint", where, limits)
            warnings.append(f"{where.label} is fixed: its <mimic> (line {mimic.sourceline}) is ignored")
    for tag, attributes in _UNUSED_NUMBERS.items():
        extra = _single(children, tag, where)
        for attribute in attributes if extra is not None else ():
            _number(extra, attribute, where, None)
    return Joint(
        name=name,
        type=kind,
        parent=links[0],
        child=links[1],
        xyz=xyz,
        rpy=rpy,
        line=element.sourceline,
        **fields,
    )


def _children(element: etree._Element) -> dict[str, list[etree._Element]]:
    """The child elements of ``element`` grouped by tag, in file order."""
    groups: dict[str, list[etree._Element]] = {}
    for child in element:
        groups.setdefault(child.tag, []).append(child)
    return groups


def _single(children: dict[str, list[etree._Element]], tag: str, where: Where) -> etree._Element | None:
    """The first ``<tag>`` child, as urdfdom and yourdfpy read it; more than one is warned about."""
    found = children.get(tag, ())
    if len(found) > 1 and where.warnings is not None:
        lines = ", ".join(str(f.sourceline) for f in found)
        where.warnings.append(
            f"{where.label} (line {found[0].getparent().sourceline}) has {len(found)} <{tag}> "
            f"elements (lines {lines}); the first one is used, as urdfdom does"
        )
    return found[0] if found else None


@overload
def _number(element: etree._Element, attribute: str, where: Where, default: float) -> float: ...
@overload
def _number(element: etree._Element, attribute: str, where: Where, default: None) -> float | None: ...
def _number(element: etree._Element, attribute: str, where: Where, default: float | None) -> float | None:
    text = element.get(attribute)
    if text is None:
        return default
    return _parse_float(text.strip(), element, attribute, where)


def _parse_float(text: str, element: etree._Element, attribute: str, where: Where) -> float:
    """One decimal number ``text`` read from ``element.get(attribute)``."""
    if not _DECIMAL.fullmatch(text):
        finite = text.lower().lstrip("+-") not in ("nan", "inf", "infinity")
        what = "is not a number" if finite else "is not finite"
    elif not math.isfinite(value := float(text)):
        what = "overflows a double"
    else:
        return value
    raise where.error(f'<{element.tag} {attribute}="{element.get(attribute)}">: {text!r} {what}', element)


def _vector(element: etree._Element, attribute: str, where: Where, default: Vector3) -> Vector3:
    """Exactly three finite numbers separated by whitespace."""
    text = element.get(attribute)
    if text is None:
        return default
    parts = text.split()
    if len(parts) != 3:
        raise where.error(
            f'<{element.tag} {attribute}="{text}">: expected three numbers separated by '
            f"spaces, got {len(parts)}",
            element,
        )
    x, y, z = (_parse_float(p, element, attribute, where) for p in parts)
    return (x, y, z)


def _origin(children: dict[str, list[etree._Element]], where: Where) -> tuple[Vector3, Vector3]:
    origin = _single(children, "origin", where)
    if origin is None:
        return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    return _vector(origin, "xyz", where, (0.0, 0.0, 0.0)), _vector(origin, "rpy", where, (0.0, 0.0, 0.0))


def _axis(children: dict[str, list[etree._Element]], where: Where, warnings: list[str]) -> Vector3:
    axis = _single(children, "axis", where)
    if axis is None:
        return (1.0, 0.0, 0.0)
    v = _vector(axis, "xyz", where, (1.0, 0.0, 0.0))
    norm = math.hypot(*v)
    if norm < _UNIT_TOLERANCE:
        raise where.error(f'<axis xyz="{axis.get("xyz")}"> is zero; give a unit axis, e.g. "0 0 1"', axis)
    if not math.isfinite(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]):  # Pinocchio and numpy would get NaN
        raise where.error(
            f'<axis xyz="{axis.get("xyz")}"> is too large: its squared norm overflows a double, '
            "so other URDF readers cannot normalize it; give a unit axis",
            axis,
        )
    if abs(norm - 1.0) <= _UNIT_TOLERANCE:
        return v
    unit = (v[0] / norm, v[1] / norm, v[2] / norm)
    warnings.append(
        f"{where.label}: axis {axis.get('xyz')!r} has norm {norm:.9g}; normalized to "
        f"({unit[0]:.9g}, {unit[1]:.9g}, {unit[2]:.9g})"
    )
    return unit


def _limits(
    children: dict[str, list[etree._Element]], element: etree._Element, kind: str, where: Where
) -> dict[str, float | None]:
    limit = _single(children, "limit", where)
    if limit is None:
        if kind == "continuous":
            return {}
        raise where.error(
            f"a {kind} joint needs a <limit lower=... upper=...> element "
            '(use type="continuous" for an unbounded revolute joint)',
            element,
        )
    out = {
        "velocity": _number(limit, "velocity", where, None),
        "effort": _number(limit, "effort", where, None),
    }
    lower, upper = _number(limit, "lower", where, 0.0), _number(limit, "upper", where, 0.0)
    if kind != "continuous":  # continuous joints ignore lower/upper (urdfdom reads but never uses them)
        if lower > upper:
            raise where.error(f"lower limit {lower!r} is greater than upper limit {upper!r}", limit)
        out.update(lower=lower, upper=upper)
    return out


def _inertial(element: etree._Element, where: Where) -> Inertial:
    children = _children(element)
    xyz, rpy = _origin(children, where)
    mass = _single(children, "mass", where)
    mass_text = None if mass is None else mass.get("value")
    if mass is None or mass_text is None:
        raise where.error("<inertial> needs <mass value=...>", element)
    value = _parse_float(mass_text.strip(), mass, "value", where)
    if value < 0:
        raise where.error(f"mass {value!r} kg is negative", mass)
    inertia = _single(children, "inertia", where)
    if inertia is None:
        raise where.error(f"<inertial> needs <inertia {' '.join(a + '=...' for a in _INERTIA)}>", element)
    texts = [inertia.get(a) for a in _INERTIA]
    missing = [a for a, text in zip(_INERTIA, texts, strict=True) if text is None]
    if missing:
        raise where.error(f"<inertia> lacks {', '.join(missing)}", inertia)
    m = [
        _parse_float(t.strip(), inertia, a, where)
        for a, t in zip(_INERTIA, texts, strict=True)
        if t is not None
    ]
    moments = (m[0], m[1], m[2], m[3], m[4], m[5])
    return Inertial(mass=value, xyz=xyz, rpy=rpy, inertia=moments)
