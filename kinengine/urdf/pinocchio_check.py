"""Pinocchio's model of a description, checked to agree with it joint for joint.

Pinocchio only ever parses :meth:`RobotDescription.to_xml`. This module builds
that model (mimic joints as ``JointModelMimic``) and confirms that it has
exactly the description's movable joints, in the description's order, with
the expected configuration sizes and parents.
"""

from __future__ import annotations

import pinocchio as pin

from ..errors import KinematicsError
from .description import RobotDescription


def build_pinocchio_model(description: RobotDescription) -> pin.Model:
    """``pin.buildModelFromXML(description.to_xml(), mimic=True)``, checked by
    :func:`check_pinocchio_model`; KinematicsError if Pinocchio fails or disagrees."""
    try:
        model = pin.buildModelFromXML(description.to_xml(), mimic=True)
    except Exception as exc:  # Pinocchio signals everything with ValueError/RuntimeError text
        raise KinematicsError(f"Pinocchio could not build {description.source}: {exc}") from None
    check_pinocchio_model(description, model)
    return model


def check_pinocchio_model(description: RobotDescription, model: pin.Model) -> None:
    """KinematicsError unless ``model`` has the description's joints in order.

    Joint i of the model (i >= 1) must be the i-th movable joint of
    ``description.joints``; a mimic joint has nq = nv = 0, a continuous joint
    nq = 2 and nv = 1, others nq = nv = 1; its parent is the nearest movable
    ancestor joint (0, the universe, if none).
    """
    movable = [j for j in description.joints if j.movable]
    names = list(model.names)[1:]
    if names != [j.name for j in movable]:
        raise KinematicsError(f"Pinocchio built the joints {names} from {description.source}, "
                              f"the description has {[j.name for j in movable]}")
    index = {j.name: i for i, j in enumerate(movable, start=1)}
    parent_joint = {j.child: j for j in description.joints}
    for i, joint in enumerate(movable, start=1):
        expected = (0, 0) if joint.mimic is not None else (2, 1) if joint.type == "continuous" else (1, 1)
        got = (model.joints[i].nq, model.joints[i].nv)
        ancestor = parent_joint.get(joint.parent)
        while ancestor is not None and not ancestor.movable:
            ancestor = parent_joint.get(ancestor.parent)
        parent = 0 if ancestor is None else index[ancestor.name]
        if got != expected or model.parents[i] != parent:
            raise KinematicsError(
                f"Pinocchio's joint {joint.name!r} has (nq, nv) = {got} and parent {model.parents[i]}, "
                f"expected {expected} and parent {parent}")
