"""An independent reference for kinengine's answers: yourdfpy parsing and plain-numpy kinematics.

It shares nothing with the Pinocchio path but the URDF text, so agreement between
the two is evidence that both are right.

>>> from kinengine.reference import ReferenceKinematics
>>> ref = ReferenceKinematics.from_urdf_string(text)
>>> ref.frame_pose(q, "tool0"), ref.jacobian(q, "tool0", reference="local")
"""

from .kinematics import REFERENCES, ReferenceKinematics
from .tree import KinematicTree, TreeJoint, read_urdf

__all__ = ["REFERENCES", "KinematicTree", "ReferenceKinematics", "TreeJoint", "read_urdf"]
