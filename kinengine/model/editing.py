"""Model editing: pure functions from one validated RobotDescription to another.

Owns :func:`add_frame` (a tool frame: a new link on a new fixed joint) and :func:`lock_joints`
(movable joints turned into fixed joints at a value). Both return a new description assembled
and validated by :func:`kinengine.urdf.tree.assemble`. :func:`edited_urdf_text` makes the robot's
URDF text say the same (new links and joints appended, locked joints rewritten as fixed ones, every
visual, collision and mesh kept): that text is what the independent reference and the viewer read,
so an edited robot is checked and drawn like any other. Units: metres, radians. Rotations follow the URDF
convention ``rpy = (roll, pitch, yaw)``: C = Rz(yaw) · Ry(pitch) · Rx(roll), about the fixed parent axes.
"""

from __future__ import annotations

import dataclasses
import math
import re
import warnings
from collections.abc import Mapping
from xml.sax.saxutils import quoteattr

import numpy as np
import numpy.typing as npt
from lxml import etree

from ..errors import ConfigurationError, FrameNotFoundError, OptionError, URDFError
from ..urdf import LIMITS, Joint, Link, RobotDescription
from ..urdf.safe_xml import parse_xml
from ..urdf.tree import assemble
from .coordinates import CoordinateMap

Vector3 = tuple[float, float, float]

_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
"""A character XML 1.0 cannot hold (NUL and other C0 controls, lone surrogates, U+FFFE, U+FFFF)."""
_ORTHONORMAL_TOLERANCE = 1e-9  # |CᵀC − 1| allowed in a (4, 4) placement's rotation block


def frame_names(description: RobotDescription) -> list[str]:
    """Every link and joint name (the frames a new frame may hang from), root first, tree order."""
    names = [description.root]
    for joint in description.joints:
        names += [joint.name, joint.child]
    return names


def add_frame(
    description: RobotDescription, name: str, parent: str, placement: npt.ArrayLike
) -> RobotDescription:
    """``description`` with a new link ``name`` fixed to frame ``parent`` at ``placement``.

    ``parent``: a link or a joint name. A joint's frame is its child link's frame (URDF: the child
    link frame sits at the joint, after the joint's motion), so the new link hangs from that child.
    ``placement``: the new frame's pose in the parent frame, a homogeneous (4, 4) T_parent,new [m],
    or a pair (xyz [m], rpy [rad]). The fixed joint is named ``<name>_joint`` (``<name>_joint_2``, ...
    if that is taken). FrameNotFoundError for an unknown parent, URDFError for a taken or empty name,
    OptionError for a name with a character XML cannot hold (e.g. NUL) or over ``Limits.max_name_length``,
    a malformed placement, or one beyond ``Limits.max_offset`` [m] (the bound URDF origins get).
    """
    known = frame_names(description)
    if not isinstance(name, str) or not name or name != name.strip() or name == "universe":
        raise URDFError(
            f"a new frame needs a non-empty name without surrounding spaces (not 'universe'), got {name!r}"
        )
    bad = _NOT_XML.search(name)
    if bad or len(name) > LIMITS.max_name_length:
        shown = f"frame name {name[:80]!r}{'...' if len(name) > 80 else ''}"
        if bad:
            raise OptionError(
                f"{shown} holds {bad.group()!r}, a character XML cannot hold (URDF text is XML); "
                "use printable characters"
            )
        raise OptionError(
            f"{shown} has {len(name)} characters, more than Limits.max_name_length = {LIMITS.max_name_length}"
        )
    if name in known:
        raise URDFError(
            f"frame name {name!r} is already used by a link or joint of {description.name!r}; "
            f"choose another name (taken: {', '.join(known[:12])}{', ...' if len(known) > 12 else ''})"
        )
    if not isinstance(parent, str) or parent not in known:
        raise FrameNotFoundError(parent, known)
    xyz, rpy = placement_xyz_rpy(placement)
    if not max(map(abs, xyz)) <= LIMITS.max_offset:
        raise OptionError(
            f"placement's xyz {list(xyz)} is beyond ±{LIMITS.max_offset:g} m (Limits.max_offset, the bound "
            "every URDF origin gets): chained frames could overflow every pose; give metres within it"
        )
    link_names = {link.name for link in description.links}
    parent_link = parent if parent in link_names else description.joint(parent).child
    joint_name, k = f"{name}_joint", 2
    while joint_name in known or joint_name == name:
        joint_name, k = f"{name}_joint_{k}", k + 1
    joint = Joint(name=joint_name, type="fixed", parent=parent_link, child=name, xyz=xyz, rpy=rpy)
    return _reassemble(description, description.links + (Link(name=name),), description.joints + (joint,))


def lock_joints(description: RobotDescription, values: Mapping[str, float]) -> RobotDescription:
    """``description`` with each named coordinate's joint fixed at its value, and its mimic followers
    at multiplier · value + offset.

    ``values``: joint name -> value [rad or m] for joints that own a coordinate. The value is folded into
    the fixed joint's origin: origin · Rot(axis, v) (revolute, continuous) or origin · Trans(v · axis)
    (prismatic). ConfigurationError for a value outside the joint's limits (as narrowed by its mimic
    followers' limits), for a mimic joint (lock its leader), an already fixed (or locked) joint or a
    non-number; FrameNotFoundError for an unknown joint.
    """
    with warnings.catch_warnings():  # the robot being edited has already said what its mimic limits imply
        warnings.simplefilter("ignore")
        coords = CoordinateMap(description)
    if not isinstance(values, Mapping):
        raise ConfigurationError(
            f"locked() takes a mapping of joint name to value, e.g. "
            f"{{{coords.names[-1]!r}: 0.0}}, got {type(values).__name__}"
        )
    fixed_joints = {j.name for j in description.joints if j.type == "fixed"}
    for joint_name in values:
        if isinstance(joint_name, str) and joint_name in fixed_joints:
            raise ConfigurationError(
                f"joint {joint_name!r} is already fixed (locked earlier, or fixed in the URDF): it has no "
                f"coordinate left to lock; the movable joints are {', '.join(coords.names) or 'none'}"
            )
    q = coords.from_mapping(values, np.clip(np.zeros(coords.dof), coords.lower, coords.upper))
    fixed: dict[str, float] = {}
    for joint_name in values:
        i = coords.names.index(joint_name)
        v, lo, hi = float(q[i]), float(coords.lower[i]), float(coords.upper[i])
        if not lo <= v <= hi:
            raise ConfigurationError(
                f"cannot lock joint {joint_name!r} at {v!r}: outside its limits "
                f"[{lo!r}, {hi!r}]; pick a value inside them"
            )
        fixed[joint_name] = v
    grown = True
    while grown:  # followers of locked joints (and their followers) are locked too
        grown = False
        for joint in description.joints:
            if joint.mimic is not None and joint.name not in fixed and joint.mimic.joint in fixed:
                m = joint.mimic
                fixed[joint.name] = m.multiplier * fixed[m.joint] + m.offset
                grown = True
    joints = tuple(_fold(j, fixed[j.name]) if j.name in fixed else j for j in description.joints)
    return _reassemble(description, description.links, joints)


def edited_urdf_text(text: str, description: RobotDescription) -> str:
    """``text`` (the URDF the unedited robot was read from) made to describe ``description``, an edit of it:
    each joint that is fixed in ``description`` but movable in ``text`` becomes a fixed joint at the
    description's origin (its axis, limits and mimic dropped); links and joints missing from ``text`` are
    appended. Everything else (visuals, meshes, materials) is kept as written. Falls back to
    :meth:`RobotDescription.to_xml` if ``text`` cannot be read again (e.g. a model over the default limits).
    """
    try:
        root = parse_xml(text, source=description.source)
    except URDFError:
        return description.to_xml()
    joints = {element.get("name"): element for element in root.findall("joint")}
    links = {element.get("name") for element in root.findall("link")}
    for joint in description.joints:
        element = joints.get(joint.name)
        if element is None:
            root.append(etree.fromstring(_joint_xml(joint)))
        elif joint.type == "fixed" and element.get("type") != "fixed":
            for child in list(element):
                if child.tag in (
                    "origin",
                    "axis",
                    "limit",
                    "mimic",
                    "dynamics",
                    "calibration",
                    "safety_controller",
                ):
                    element.remove(child)
            element.set("type", "fixed")
            element.insert(0, etree.fromstring(f'<origin xyz="{_v(joint.xyz)}" rpy="{_v(joint.rpy)}"/>'))
    for link in description.links:
        if link.name not in links:
            root.append(etree.fromstring(f"<link name={quoteattr(link.name)}/>"))
    return etree.tostring(root, encoding="unicode") + "\n"


def placement_xyz_rpy(placement: npt.ArrayLike) -> tuple[Vector3, Vector3]:
    """(xyz [m], rpy [rad]) of a (4, 4) homogeneous transform or of an (xyz, rpy) pair; OptionError
    otherwise."""
    if (isinstance(placement, (tuple, list)) and len(placement) == 2) or np.shape(placement) == (2, 3):
        try:
            pair = placement if isinstance(placement, (tuple, list)) else np.asarray(placement)
            xyz, rpy = (np.asarray(p, dtype=float) for p in pair)
        except (TypeError, ValueError):
            xyz = rpy = np.zeros(0)
        if xyz.shape == (3,) and rpy.shape == (3,) and np.isfinite(xyz).all() and np.isfinite(rpy).all():
            return _vector(xyz), _vector(rpy)
    try:
        T = np.asarray(placement, dtype=float)
    except (TypeError, ValueError):
        T = np.zeros(0)
    if T.shape != (4, 4) or not np.isfinite(T).all():
        raise OptionError(
            f"placement must be a (4, 4) homogeneous transform or a pair (xyz [m], rpy [rad]) of "
            f"three numbers each, got {_describe(placement)}"
        )
    C = T[:3, :3]
    if (
        not np.allclose(T[3], (0.0, 0.0, 0.0, 1.0), rtol=0.0, atol=0.0)
        or np.abs(C.T @ C - np.eye(3)).max() > _ORTHONORMAL_TOLERANCE
        or np.linalg.det(C) < 0
    ):
        raise OptionError(
            "placement (4, 4) must be homogeneous: a rotation matrix (orthonormal, det +1) in "
            "[:3, :3] and a last row (0, 0, 0, 1)"
        )
    return _vector(T[:3, 3]), rpy_from_matrix(C)


def matrix_from_rpy(rpy: Vector3) -> npt.NDArray[np.float64]:
    """C = Rz(yaw) · Ry(pitch) · Rx(roll), (3, 3): the URDF's rpy convention."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def rpy_from_matrix(C: np.ndarray) -> Vector3:
    """(roll, pitch, yaw) [rad] with C = Rz(yaw) · Ry(pitch) · Rx(roll); at pitch = ±π/2 yaw is 0.

    Roll is read from Ry(pitch)ᵀ · Rz(yaw)ᵀ · C, not from C's last row: near pitch = ±π/2 the yaw
    read from C is off by ε/cos(pitch), and this roll absorbs that error, so that
    ``matrix_from_rpy(rpy_from_matrix(C))`` is C to rounding at every pitch."""
    cp = math.hypot(C[0, 0], C[1, 0])
    pitch = math.atan2(-C[2, 0], cp)
    yaw = math.atan2(C[1, 0], C[0, 0]) if cp > 0.0 else 0.0
    A = matrix_from_rpy((0.0, pitch, yaw)).T @ np.asarray(C, dtype=float)  # Rx(roll) to rounding
    return (math.atan2(A[2, 1], A[2, 2]), pitch, yaw)


def _fold(joint: Joint, value: float) -> Joint:
    """A fixed joint whose origin is the movable joint's origin composed with its motion at ``value``."""
    C0 = matrix_from_rpy(joint.rpy)
    axis = np.asarray(joint.axis, dtype=float)
    p = np.asarray(joint.xyz, dtype=float)
    if joint.type == "prismatic":
        p, C = p + C0 @ (value * axis), C0
    else:
        C = C0 @ _axis_angle(axis, value)
    return dataclasses.replace(
        joint, type="fixed", xyz=_vector(p), rpy=rpy_from_matrix(C), lower=None, upper=None, mimic=None
    )


def _axis_angle(axis: np.ndarray, angle: float) -> npt.NDArray[np.float64]:
    """Rodrigues: rotation by ``angle`` [rad] about the unit ``axis``, (3, 3)."""
    x, y, z = axis
    K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


def _reassemble(
    description: RobotDescription, links: tuple[Link, ...], joints: tuple[Joint, ...]
) -> RobotDescription:
    return assemble(description.name, links, joints, source=description.source, warnings=description.warnings)


def _joint_xml(joint: Joint) -> str:
    """A fixed joint's URDF element."""
    return (
        f'<joint name={quoteattr(joint.name)} type="fixed"><parent link={quoteattr(joint.parent)}/>'
        f'<child link={quoteattr(joint.child)}/><origin xyz="{_v(joint.xyz)}" rpy="{_v(joint.rpy)}"/></joint>'
    )


def _v(v: Vector3) -> str:
    return " ".join(repr(float(x)) for x in v)


def _vector(v: np.ndarray) -> Vector3:
    return (float(v[0]), float(v[1]), float(v[2]))


def _describe(value: object) -> str:
    shape = getattr(value, "shape", None)
    return f"an array of shape {shape}" if shape is not None else f"{type(value).__name__} {value!r:.60}"


__all__ = [
    "add_frame",
    "edited_urdf_text",
    "frame_names",
    "lock_joints",
    "matrix_from_rpy",
    "placement_xyz_rpy",
    "rpy_from_matrix",
]
