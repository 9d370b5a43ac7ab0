"""The kinematics layer: poses and Jacobians at single configurations (:mod:`.engine`), over batches
(:mod:`.batch`), and their derivatives (:mod:`.derivatives`), all on one per-robot
:class:`~kinengine.kinematics.engine.Kinematics` object."""

from .engine import REFERENCES, Kinematics, resolve_reference

__all__ = ["REFERENCES", "Kinematics", "resolve_reference"]
