"""Pinocchio's model of a validated description: one plain joint per movable URDF joint.

Pinocchio's C++ parser only ever reads :func:`pinocchio_xml`, regenerated from the validated
description: revolute and continuous joints become revolute joints with nq = nv = 1 (a continuous
joint is a revolute joint without limits), prismatic joints prismatic, and mimic joints ordinary
independent joints (kinengine's coordinate map drives them, see :mod:`kinengine.model.coordinates`).
Numbers kinematics never needs (effort, velocity) are written in a form Pinocchio accepts. The
model is then checked joint for joint against the description.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin

from ..errors import URDFError
from ..urdf import RobotDescription
from .stack import call_with_big_stack, stack_for_depth, stack_needed

_UNBOUNDED = float(np.finfo(np.float64).max)


def pinocchio_xml(description: RobotDescription) -> str:
    """The canonical URDF that Pinocchio parses: continuous joints as revolute with placeholder limits
    (replaced by ±max float after the build), no <mimic> tags, effort/velocity ≥ 0."""
    joints = []
    for j in description.joints:
        if j.movable:
            j = dataclasses.replace(
                j,
                type="revolute" if j.type == "continuous" else j.type,
                mimic=None,
                lower=-np.pi if j.lower is None else j.lower,
                upper=np.pi if j.upper is None else j.upper,
                effort=_nonnegative(j.effort),
                velocity=_nonnegative(j.velocity),
            )
        joints.append(j)
    return dataclasses.replace(description, joints=tuple(joints)).to_xml()


def build_pinocchio_model(description: RobotDescription) -> pin.Model:
    """Pinocchio's Model of ``description`` (see the module doc), checked by :func:`check_pinocchio_model`.
    URDFError (naming the file) if Pinocchio fails or disagrees."""
    try:
        model = _build(pinocchio_xml(description), _depth(description))
    except Exception as exc:  # Pinocchio signals everything with ValueError/RuntimeError text
        raise _pinocchio_error(description, exc) from None
    check_pinocchio_model(description, model)
    for joint in description.joints:
        if joint.type == "continuous":
            idx = model.joints[model.getJointId(joint.name)].idx_q
            model.lowerPositionLimit[idx], model.upperPositionLimit[idx] = -_UNBOUNDED, _UNBOUNDED
    return model


def check_pinocchio_model(description: RobotDescription, model: pin.Model) -> None:
    """URDFError unless ``model`` has the description's movable joints in order, each with
    nq = nv = 1 and its parent the nearest movable ancestor joint (0, the universe, if none)."""
    movable = [j for j in description.joints if j.movable]
    names = list(model.names)[1:]
    if names != [j.name for j in movable]:
        raise URDFError(
            f"Pinocchio built the joints {names} from {description.source}, "
            f"the description has {[j.name for j in movable]}"
        )
    index = {j.name: i for i, j in enumerate(movable, start=1)}
    parent_joint = {j.child: j for j in description.joints}
    for i, joint in enumerate(movable, start=1):
        got = (model.joints[i].nq, model.joints[i].nv)
        ancestor = parent_joint.get(joint.parent)
        while ancestor is not None and not ancestor.movable:
            ancestor = parent_joint.get(ancestor.parent)
        parent = 0 if ancestor is None else index[ancestor.name]
        if got != (1, 1) or model.parents[i] != parent or model.joints[i].idx_q != i - 1:
            raise URDFError(
                f"Pinocchio's joint {joint.name!r} has (nq, nv) = {got} and parent "
                f"{model.parents[i]}, expected (1, 1) and parent {parent}"
            )


def _pinocchio_error(description: RobotDescription, exc: Exception) -> URDFError:
    """A URDFError with Pinocchio's reason, naming the first joint whose addition makes the build fail
    (found by bisection over prefixes of the tree order: each prefix is a subtree; ~log2(joints) builds)."""
    reason = f"Pinocchio could not build it: {' '.join(str(exc).split())}"
    lo, hi = 0, len(description.joints)  # the prefix of lo joints builds, of hi joints fails
    while hi - lo > 1:
        mid = (lo + hi) // 2
        sub = dataclasses.replace(
            description, joints=description.joints[:mid], links=description.links[: mid + 1]
        )
        try:
            _build(pinocchio_xml(sub), _depth(sub))
            lo = mid
        except Exception:
            hi = mid
    if hi == 0:
        return URDFError(reason, source=description.source)
    joint = description.joints[hi - 1]
    return URDFError(reason, source=description.source, element=f"joint {joint.name!r}", line=joint.line)


def _build(xml: str, depth: int) -> pin.Model:
    """``pin.buildModelFromXML(xml)`` on a thread with a known stack, big enough for a tree ``depth`` levels
    deep: Pinocchio's parser recurses once per level and a small thread stack would overflow (see
    :mod:`kinengine.model.stack`)."""
    build = lambda: pin.buildModelFromXML(xml)  # noqa: E731
    return call_with_big_stack(build, stack_for_depth(depth), stack_needed(depth))


def _depth(description: RobotDescription) -> int:
    """The most joints (fixed ones included) between the root and any link."""
    depth = {description.root: 0}
    for joint in description.joints:  # depth-first order: a parent is seen before its children
        depth[joint.child] = depth.get(joint.parent, 0) + 1
    return max(depth.values())


def _nonnegative(value: float | None) -> float | None:
    """Effort and velocity limits as Pinocchio accepts them: a negative one (URDF files use -1 for
    "unknown") becomes None (written as 0); kinengine keeps the file's own numbers."""
    return value if value is not None and value >= 0.0 else None


__all__ = ["build_pinocchio_model", "check_pinocchio_model", "pinocchio_xml"]
