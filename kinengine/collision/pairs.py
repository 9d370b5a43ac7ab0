"""Which collision shapes are checked against which: adjacent links excluded, an SRDF's
``<disable_collisions>`` honoured, and a sampling search for never- and always-colliding link pairs (as
MoveIt's setup assistant does).

A pair is named by its two link names (an obstacle by its own name). Shapes on one rigid body (the same
Pinocchio joint: a link and the links fixed to it) never move relative to each other and are never paired;
two links are adjacent when one joint connects them, links without collision shapes skipped (the Panda's
``panda_link8`` between ``panda_link7`` and ``panda_hand``). Obstacles are paired with every shape that
moves (not with the base, which stays where it is).
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np
import pinocchio as pin

from ..errors import OptionError, URDFError
from ..urdf.safe_xml import parse_xml

LinkPair = tuple[str, str]


def link_of(model: pin.Model, geometry: pin.GeometryModel, index: int) -> str:
    """The link (frame) name a shape hangs on; an obstacle's own name."""
    obj = geometry.geometryObjects[index]
    frame = obj.parentFrame
    if obj.parentJoint == 0 and frame == 0:
        return str(obj.name)
    return str(model.frames[frame].name)


def adjacent_pairs(model: pin.Model, geometry: pin.GeometryModel, n_robot: int) -> set[frozenset[int]]:
    """Pinocchio joint pairs {a, b} whose shapes are adjacent (module doc), among the first ``n_robot``
    shapes."""
    carries = {int(geometry.geometryObjects[i].parentJoint) for i in range(n_robot)}
    out: set[frozenset[int]] = set()
    for joint in carries:
        parent = joint
        while parent != 0:
            parent = int(model.parents[parent])
            if parent in carries:
                break
        if parent != joint:
            out.add(frozenset((joint, parent)))
    return out


def default_pairs(
    model: pin.Model,
    geometry: pin.GeometryModel,
    n_robot: int,
    disabled: Iterable[frozenset[str]] = (),
) -> list[tuple[int, int]]:
    """Shape index pairs (i < j) to check: robot shapes on different, non-adjacent bodies whose link pair is
    not ``disabled``, then every moving robot shape against every obstacle (index >= n_robot)."""
    adjacent = adjacent_pairs(model, geometry, n_robot)
    off = {frozenset(p) for p in disabled}
    joints = [int(obj.parentJoint) for obj in geometry.geometryObjects]
    links = [link_of(model, geometry, i) for i in range(geometry.ngeoms)]
    pairs = []
    for i in range(n_robot):
        for j in range(i + 1, geometry.ngeoms):
            if j < n_robot:
                if joints[i] == joints[j] or frozenset((joints[i], joints[j])) in adjacent:
                    continue
            elif joints[i] == 0:
                continue
            if frozenset((links[i], links[j])) in off:
                continue
            pairs.append((i, j))
    return pairs


def read_disabled_pairs(srdf: str | os.PathLike[str]) -> set[frozenset[str]]:
    """The link pairs of an SRDF's ``<disable_collisions link1= link2=>`` elements; ``srdf`` is a file or
    the SRDF text itself. URDFError for unreadable XML or an element without both links."""
    if not isinstance(srdf, (str, os.PathLike)):
        raise OptionError(f"srdf is a file name or the SRDF text, got {type(srdf).__name__}")
    text = os.fspath(srdf)
    source = "<string>"
    if not isinstance(text, str) or not text.lstrip().startswith("<"):
        try:
            path = Path(os.fsdecode(text)).expanduser()
            found = path.is_file()
        except (ValueError, OSError):  # a NUL byte, a name too long for the system
            found = False
        if not found:
            raise URDFError(f"SRDF file {os.fsdecode(text)[:200]!r} not found (pass a path or the SRDF text)")
        source, text = str(path), path.read_text(encoding="utf-8", errors="replace")
    root = parse_xml(text, source=source)
    out = set()
    for element in root.iter("disable_collisions"):
        a, b = element.get("link1"), element.get("link2")
        if not a or not b:
            raise URDFError(
                "<disable_collisions> needs link1 and link2", source=source, line=element.sourceline
            )
        out.add(frozenset((a, b)))
    return out


def warn_unknown_links(disabled: Iterable[frozenset[str]], known: Iterable[str]) -> None:
    """One UserWarning naming the links of ``disabled`` pairs that are not in ``known`` (the robot's links
    and obstacles), as MoveIt warns: such a pair disables nothing, often a sign of an SRDF for another
    robot or a renamed link."""
    names = set(known)
    unknown = sorted({name for pair in disabled for name in pair} - names)
    if unknown:
        shown = ", ".join(repr(n) for n in unknown[:10]) + (", ..." if len(unknown) > 10 else "")
        warnings.warn(
            f"the SRDF's <disable_collisions> name {len(unknown)} link{'s' if len(unknown) > 1 else ''} "
            f"this robot does not have: {shown}; those pairs disable nothing (an SRDF of another robot?)",
            UserWarning,
            stacklevel=4,  # the caller of Robot.with_srdf / collision_pairs
        )


def sample_pairs(
    collides: Callable[[np.ndarray], np.ndarray], Q: np.ndarray, names: Sequence[LinkPair]
) -> tuple[list[LinkPair], list[LinkPair]]:
    """(never, always): the link pairs that collide in none / in every configuration of Q (N, dof).

    ``collides(q)`` is a bool array (P,) over the shape pairs named ``names``; a link pair collides when one
    of its shape pairs does."""
    counts = dict.fromkeys(names, 0)
    for q in Q:
        for name in {names[int(k)] for k in np.flatnonzero(collides(q))}:
            counts[name] += 1
    never = [p for p, c in counts.items() if c == 0]
    always = [p for p, c in counts.items() if c == len(Q)]
    return never, always


def write_srdf(robot_name: str, reasons: Iterable[tuple[LinkPair, str]]) -> str:
    """An SRDF holding one ``<disable_collisions>`` per (link pair, reason): "Adjacent", "Never", ..."""
    lines = ['<?xml version="1.0"?>', f"<robot name={quoteattr(robot_name)}>"]
    for (a, b), reason in reasons:
        lines.append(
            f"  <disable_collisions link1={quoteattr(a)} link2={quoteattr(b)} reason={quoteattr(reason)}/>"
        )
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


__all__ = [
    "LinkPair",
    "adjacent_pairs",
    "default_pairs",
    "link_of",
    "read_disabled_pairs",
    "sample_pairs",
    "warn_unknown_links",
    "write_srdf",
]
