"""Assembling links and joints into one validated kinematic tree.

Rules: unique link and joint names; every joint's parent and child exist; no
link has two parents; exactly one root; no cycles; every link reachable; mimic
joints follow an existing movable joint (a mimic of a mimic is resolved to its
root leader; a cycle of mimic joints is refused).

Order: joints depth-first from the root, the child joints of a link sorted by
name (byte order of UTF-8), which is the order urdfdom stores them in and so
the order Pinocchio builds its joints in. Links: the root, then each joint's
child in joint order (``links[i + 1] is joints[i].child``). All traversals are
iterative: a 10,000-link chain needs no recursion, in any thread.
"""

from __future__ import annotations

import difflib
from collections.abc import Sequence

from ..errors import URDFError
from .description import Joint, Link, RobotDescription
from .limits import LIMITS, Limits


def assemble(
    name: str,
    links: Sequence[Link],
    joints: Sequence[Joint],
    *,
    source: str,
    warnings: Sequence[str] = (),
    limits: Limits = LIMITS,
) -> RobotDescription:
    """The validated :class:`RobotDescription` of these links and joints (file order in, tree order out)."""
    if not links:
        raise URDFError("the robot has no <link>", source=source, element=f"robot {name!r}")
    link_by_name = _unique(links, "link", source)
    joint_by_name = _unique(joints, "joint", source)
    parent_joint: dict[str, Joint] = {}
    children: dict[str, list[Joint]] = {link.name: [] for link in links}
    for joint in joints:
        for role in ("parent", "child"):
            link = getattr(joint, role)
            if link not in link_by_name:
                raise _error(
                    f"its {role} link {link!r} is not defined{_hint(link, link_by_name)}", joint, source
                )
        if joint.parent == joint.child:
            raise _error(f"connects link {joint.child!r} to itself (a cycle)", joint, source)
        if joint.child in parent_joint:
            first = parent_joint[joint.child]
            raise _error(
                f"link {joint.child!r} already has parent joint {first.name!r} (line {first.line}); "
                "a link can have only one parent in a URDF tree",
                joint,
                source,
            )
        parent_joint[joint.child] = joint
        children[joint.parent].append(joint)
    roots = [link.name for link in links if link.name not in parent_joint]
    if not roots:
        raise URDFError(f"there is no root link: {_cycle(links[0].name, parent_joint)}", source=source)
    if len(roots) > 1:
        named = ", ".join(repr(r) for r in roots[:10]) + (", ..." if len(roots) > 10 else "")
        raise URDFError(
            f"the links form {len(roots)} separate trees, with roots {named}; a robot is one "
            "tree: connect them with joints or remove the extra links",
            source=source,
        )
    ordered = _depth_first(roots[0], children, limits.max_tree_depth, source)
    if len(ordered) < len(joints):
        reached = {roots[0]} | {j.child for j in ordered}
        unreached = next(link.name for link in links if link.name not in reached)
        raise URDFError(
            f"not every link hangs from root {roots[0]!r}: {_cycle(unreached, parent_joint)}", source=source
        )
    _check_mimics(ordered, joint_by_name, source)
    tree_links = (link_by_name[roots[0]],) + tuple(link_by_name[j.child] for j in ordered)
    return RobotDescription(
        name=name,
        root=roots[0],
        links=tree_links,
        joints=tuple(ordered),
        source=source,
        warnings=tuple(warnings),
    )


def _unique(items: Sequence[Link] | Sequence[Joint], kind: str, source: str) -> dict:
    by_name: dict = {}
    for item in items:
        if item.name in by_name:
            raise URDFError(
                f"{kind} name {item.name!r} is used twice (lines {by_name[item.name].line} and "
                f"{item.line}); names must be unique",
                source=source,
                element=f"{kind} {item.name!r}",
                line=item.line,
            )
        by_name[item.name] = item
    return by_name


def _depth_first(root: str, children: dict[str, list[Joint]], max_depth: int, source: str) -> list[Joint]:
    """Joints reachable from ``root``, depth-first, siblings by name (byte order); URDFError if too deep."""
    order: list[Joint] = []
    stack = [(joint, 1) for joint in sorted(children[root], key=_byte_name, reverse=True)]
    while stack:
        joint, depth = stack.pop()
        if depth > max_depth:
            raise URDFError(
                f"link {joint.child!r} is more than Limits.max_tree_depth = {max_depth} joints "
                f"below the root {root!r}",
                source=source,
                element=f"joint {joint.name!r}",
                line=joint.line,
            )
        order.append(joint)
        stack.extend((j, depth + 1) for j in sorted(children[joint.child], key=_byte_name, reverse=True))
    return order


def _byte_name(joint: Joint) -> bytes:
    return joint.name.encode("utf-8", errors="surrogatepass")


def _cycle(start: str, parent_joint: dict[str, Joint]) -> str:
    """A description of the cycle met by walking up from ``start`` (every link on the way has a parent)."""
    seen: dict[str, int] = {}
    path: list[Joint] = []
    link = start
    while link not in seen:
        seen[link] = len(path)
        joint = parent_joint[link]
        path.append(joint)
        link = joint.parent
    loop = path[seen[link] :][::-1]
    chain = " -> ".join([repr(loop[0].parent)] + [f"{j.child!r}" for j in loop])
    joints = ", ".join(repr(j.name) for j in loop)
    return f"joints {joints} form a cycle {chain}; a URDF must be a tree"


def _check_mimics(ordered: list[Joint], joint_by_name: dict[str, Joint], source: str) -> None:
    """Each mimic joint follows an existing movable joint of any type, before or after it in joint
    order; a mimic of a mimic is fine (it composes down to its root leader), a cycle of mimics is not."""
    for joint in ordered:
        if joint.mimic is None:
            continue
        target = joint.mimic.joint
        if target == joint.name:
            raise _error("mimics itself; a mimic joint must follow another joint", joint, source)
        leader = joint_by_name.get(target)
        if leader is None:
            raise _error(
                f"mimics joint {target!r}, which is not defined{_hint(target, joint_by_name)}", joint, source
            )
        if not leader.movable:
            raise _error(
                f"mimics joint {target!r}, which is fixed; a mimic leader must be revolute, "
                "continuous or prismatic",
                joint,
                source,
            )
        seen = [joint.name]
        while leader.mimic is not None:  # follow the chain to its root leader
            seen.append(leader.name)
            if leader.mimic.joint not in joint_by_name:
                break  # reported when that joint is checked
            leader = joint_by_name[leader.mimic.joint]
            if leader.name in seen:
                cycle = " -> ".join(repr(n) for n in seen[seen.index(leader.name) :] + [leader.name])
                raise _error(
                    f"is part of a cycle of mimic joints {cycle}; one of them must be independent",
                    joint,
                    source,
                )


def _hint(name: str, known: dict) -> str:
    close = difflib.get_close_matches(name, list(known), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _error(message: str, joint: Joint, source: str) -> URDFError:
    return URDFError(message, source=source, element=f"joint {joint.name!r}", line=joint.line)
