"""Strict URDF reading with yourdfpy, and the kinematic tree the reference walks.

Nothing here touches Pinocchio or :mod:`kinengine.urdf`: the URDF text is read
by expat as urdfdom reads it (strict, no namespaces, no DTD) and then by yourdfpy, whose joint origins
T_{parent,joint} = Trans(xyz) · Rz(yaw) · Ry(pitch) · Rx(roll) are used as given.
"""

from __future__ import annotations

import io
import re
from collections.abc import Mapping
from dataclasses import dataclass
from xml.parsers import expat

import numpy as np
import yourdfpy
from lxml import etree

from ..errors import URDFError

SUPPORTED_TYPES = ("revolute", "continuous", "prismatic", "fixed")


def read_urdf(text: str | bytes, *, source: str = "<string>", scene_graph: bool = False) -> yourdfpy.URDF:
    """Parse URDF text with yourdfpy, refusing anything that is not well-formed XML.

    ``yourdfpy.URDF.load`` silently re-parses malformed XML in lxml's recover
    mode (dropping what it cannot read), and it knows no namespace-free reading. So the
    text is first read strictly as urdfdom's TinyXML reads it (:func:`plain_urdf`) and
    yourdfpy gets that clean document, whose parse never needs recovering, without its
    ``<collision>`` elements (kinematics needs none, and yourdfpy refuses the ``<capsule>`` that
    kinengine's collision reader takes). Meshes are never loaded; ``scene_graph=True`` builds
    yourdfpy's own forward kinematics.
    """
    data = plain_urdf(text, source=source, leave_out=("collision",))
    try:
        return yourdfpy.URDF.load(
            io.BytesIO(data),
            build_scene_graph=scene_graph,
            build_collision_scene_graph=False,
            load_meshes=False,
            load_collision_meshes=False,
        )
    except Exception as exc:  # yourdfpy signals bad attributes with assorted builtin errors
        raise URDFError(f"yourdfpy could not read it: {type(exc).__name__}: {exc}", source=source) from None


def plain_urdf(text: str | bytes, *, source: str = "<string>", leave_out: tuple[str, ...] = ()) -> bytes:
    """The document as urdfdom (TinyXML, which knows no namespaces) reads it, re-serialized as plain XML.

    Read by expat without namespace processing, so a name is just its text: an element or attribute
    whose name has a prefix (``<sensor:camera>`` in a ``<gazebo>`` block, declared or not) is no URDF and
    is left out with its contents, as are ``xmlns`` declarations (so ``<robot xmlns="...">`` is
    ``<robot>``), comments and processing instructions. A DOCTYPE (and so any entity declaration) and
    malformed XML are refused with a URDFError; the root must be ``<robot>``. Elements named in
    ``leave_out`` are left out with their contents too.
    """
    data = text.encode("utf-8") if isinstance(text, str) else bytes(text)
    if isinstance(text, str):  # the bytes are UTF-8 whatever the declaration says
        data = re.sub(rb"\A(<\?xml[^>]*?encoding\s*=\s*)([\"'])[^\"']*\2", rb"\1\2UTF-8\2", data, count=1)
    builder, skipping = etree.TreeBuilder(), [0]  # depth inside a left-out element

    def start(name: str, attributes: dict[str, str]) -> None:
        if skipping[0] or ":" in name or name in leave_out:
            skipping[0] += 1
        else:
            builder.start(name, {k: v for k, v in attributes.items() if ":" not in k and k != "xmlns"})

    def end(name: str) -> None:
        if skipping[0]:
            skipping[0] -= 1
        else:
            builder.end(name)

    def refuse_dtd(*_: object) -> None:
        raise URDFError(
            "a <!DOCTYPE> is not read: no DTD, no entity declarations",
            source=source,
            line=parser.CurrentLineNumber,
        )

    parser = expat.ParserCreate()  # no namespace_separator: no namespace processing, as TinyXML
    parser.StartElementHandler, parser.EndElementHandler = start, end
    parser.CharacterDataHandler = lambda chars: None if skipping[0] else builder.data(chars)
    parser.StartDoctypeDeclHandler = refuse_dtd
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise URDFError(
            f"not well-formed XML: {expat.errors.messages[exc.code]}", source=source, line=exc.lineno
        ) from None
    root = builder.close()
    if root.tag != "robot":
        raise URDFError(f"the root element is <{root.tag}>, expected <robot>", source=source)
    return etree.tostring(root, encoding="utf-8")


@dataclass(frozen=True, eq=False)
class TreeJoint:
    """One URDF joint: the constant origin T_{parent,joint} (4, 4) and the unit axis in the joint frame.

    The joint frame is the child link frame. Mimic joints (``leader`` set) follow
    q = multiplier · q_leader + offset (the leader may itself be a mimic joint, see
    :func:`resolve_mimic`); fixed joints carry no mimic.
    """

    name: str
    kind: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    leader: str | None = None
    multiplier: float = 1.0
    offset: float = 0.0

    @property
    def movable(self) -> bool:
        return self.kind != "fixed"


@dataclass(frozen=True)
class KinematicTree:
    """A validated URDF tree: one root link, every other link the child of exactly one joint.

    ``joints`` is in depth-first order from the root, children in file order.
    """

    name: str
    root: str
    joints: tuple[TreeJoint, ...]
    parent_joint: Mapping[str, int]  # link name -> index in joints of the joint whose child it is

    @classmethod
    def from_urdf(cls, urdf: yourdfpy.URDF, *, source: str = "<string>") -> KinematicTree:
        robot = urdf.robot
        links = [link.name for link in robot.links]
        _unique(links, "link", source)
        _unique([j.name for j in robot.joints], "joint", source)
        known = set(links)
        by_parent: dict[str, list[TreeJoint]] = {name: [] for name in links}
        parent_of: dict[str, str] = {}
        for j in robot.joints:
            joint = _tree_joint(j, source)
            for role, link in (("parent", joint.parent), ("child", joint.child)):
                if link not in known:
                    raise URDFError(
                        f"{role} link {link!r} is not defined", source=source, element=f"joint {joint.name!r}"
                    )
            if joint.child in parent_of:
                raise URDFError(
                    f"link {joint.child!r} is the child of both {parent_of[joint.child]!r} "
                    f"and {joint.name!r}",
                    source=source,
                    element=f"joint {joint.name!r}",
                )
            parent_of[joint.child] = joint.name
            by_parent[joint.parent].append(joint)
        roots = [name for name in links if name not in parent_of]
        if len(roots) != 1:
            raise URDFError(
                f"expected exactly one root link, found {roots or 'none (a cycle)'}", source=source
            )
        ordered: list[TreeJoint] = []
        stack = list(reversed(by_parent[roots[0]]))
        while stack:  # depth-first, children in file order
            joint = stack.pop()
            ordered.append(joint)
            stack.extend(reversed(by_parent[joint.child]))
        if len(ordered) != len(robot.joints):
            cut = sorted(set(parent_of) - {j.child for j in ordered})
            raise URDFError(
                f"links {cut} are not connected to the root {roots[0]!r} (a cycle)", source=source
            )
        _check_mimics(ordered, source)
        return cls(robot.name, roots[0], tuple(ordered), {j.child: i for i, j in enumerate(ordered)})

    def chain(self, link: str) -> list[TreeJoint]:
        """The joints from the root down to ``link``, root first (the factors of T_IF = Π T_{k-1,k})."""
        chain = []
        while link != self.root:
            joint = self.joints[self.parent_joint[link]]
            chain.append(joint)
            link = joint.parent
        return chain[::-1]

    @property
    def independent_joints(self) -> tuple[str, ...]:
        """Movable joints that own a coordinate (mimic joints excluded), in depth-first order."""
        return tuple(j.name for j in self.joints if j.movable and j.leader is None)

    @property
    def frames(self) -> dict[str, str]:
        """Frame name -> link it is attached to: every link, and every joint (at its child link).

        A link wins over a joint of the same name. Order: the root, then per joint (depth-first)
        the joint and its child link.
        """
        links = {self.root} | {j.child for j in self.joints}
        frames = {self.root: self.root}
        for j in self.joints:
            if j.name not in links:
                frames[j.name] = j.child
            frames[j.child] = j.child
        return frames


def _tree_joint(j: yourdfpy.Joint, source: str) -> TreeJoint:
    where = f"joint {j.name!r}"
    if j.type not in SUPPORTED_TYPES:
        raise URDFError(
            f"joint type {j.type!r} is not supported (use one of {', '.join(SUPPORTED_TYPES)})",
            source=source,
            element=where,
        )
    origin = np.eye(4) if j.origin is None else np.array(j.origin, dtype=float)
    if not np.all(np.isfinite(origin)):
        raise URDFError("<origin> has non-finite values", source=source, element=where)
    axis = np.array([1.0, 0.0, 0.0]) if j.axis is None else np.array(j.axis, dtype=float)
    norm = float(np.linalg.norm(axis)) if axis.shape == (3,) else 0.0
    if j.type != "fixed" and not (np.isfinite(norm) and norm > 1e-12):
        raise URDFError(
            f"<axis xyz> must be a finite non-zero 3-vector, got {axis.tolist()}",
            source=source,
            element=where,
        )
    mimic = j.mimic if j.type != "fixed" else None  # a fixed joint has nothing to mimic
    if mimic is not None and (mimic.joint is None or not np.isfinite([mimic.multiplier, mimic.offset]).all()):
        raise URDFError(
            "<mimic> needs a joint name and finite multiplier and offset", source=source, element=where
        )
    axis = axis / norm if norm else axis
    origin.flags.writeable = axis.flags.writeable = False
    return TreeJoint(
        j.name,
        j.type,
        j.parent,
        j.child,
        origin,
        axis,
        None if mimic is None else mimic.joint,
        1.0 if mimic is None else float(mimic.multiplier),
        0.0 if mimic is None else float(mimic.offset),
    )


def _check_mimics(joints: list[TreeJoint], source: str) -> None:
    """Every mimic joint follows an existing movable joint (of any type, anywhere in the tree); a chain
    of mimics must end at an independent joint (no cycle)."""
    by_name = {j.name: j for j in joints}
    for j in joints:
        if j.leader is None:
            continue
        leader = by_name.get(j.leader)
        problem = "does not exist" if leader is None else "is fixed" if not leader.movable else None
        if problem:
            raise URDFError(
                f"mimics joint {j.leader!r}, which {problem}", source=source, element=f"joint {j.name!r}"
            )
        chain = [j.name]
        while leader is not None and leader.leader is not None:
            if leader.name in chain:
                raise URDFError(
                    f"mimic joints {chain} form a cycle", source=source, element=f"joint {j.name!r}"
                )
            chain.append(leader.name)
            leader = by_name.get(leader.leader)


def resolve_mimic(joints: Mapping[str, TreeJoint], name: str) -> tuple[str, float, float]:
    """(independent joint, a, b) with q_name = a · q_independent + b, following a chain of mimic joints:
    q_name = m₁ q₁ + o₁, q₁ = m₂ q₂ + o₂, ... composed step by step (a ← a·m, b ← a·o + b)."""
    a, b, joint = 1.0, 0.0, joints[name]
    while joint.leader is not None:
        a, b = a * joint.multiplier, a * joint.offset + b
        joint = joints[joint.leader]
    return joint.name, a, b


def _unique(names: list[str], kind: str, source: str) -> None:
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise URDFError(f"two {kind}s are named {name!r}", source=source, element=f"{kind} {name!r}")
        seen.add(name)
