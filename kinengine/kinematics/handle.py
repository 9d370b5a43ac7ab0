"""A frame handle for hot loops: one frame's pose and Jacobian with everything looked up once.

>>> fk = robot.frame("tool0")                  # FrameHandle; check_inputs=False skips the input check
>>> T = fk.pose(q)                             # T_IF (4, 4) [m] in the root link frame I
>>> J = fk.jacobian(q, reference="local")      # (6, dof), rows [linear; angular]
>>> T, J = fk.kinematics(q)                    # both from one pass, equal to the two calls above

Same frames, units and references as :mod:`kinengine.kinematics.engine`. The handle binds
Pinocchio's model, the frame index and Pinocchio's functions once; each thread gets its own
Pinocchio Data (and, for robots with mimic joints, its own buffer for q_pin = M q + b), so one
handle serves several threads. With ``check_inputs=True`` every call runs the one input check,
:meth:`CoordinateMap.check` (single configurations only: q of shape (dof,)). With
``check_inputs=False`` the caller promises a C-contiguous float64 array of shape (dof,) with finite
entries; anything else is undefined behaviour of Pinocchio (wrong numbers or an exception),
never checked.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ..arrays import Reference
from .engine import REFERENCES, Kinematics, resolve_reference


class FrameHandle:
    """Pose and Jacobian of one frame at single configurations q (dof,); see the module doc."""

    __slots__ = ("check_inputs", "dof", "frame_id", "jacobian", "kinematics", "name", "pose")

    pose: Callable[[np.ndarray], np.ndarray]
    jacobian: Callable[..., np.ndarray]
    kinematics: Callable[..., tuple[np.ndarray, np.ndarray]]

    def __init__(self, kin: Kinematics, frame: str, *, check_inputs: bool = True) -> None:
        if type(check_inputs) is not bool:
            from ..errors import OptionError

            raise OptionError(f"`check_inputs` must be True or False, got {check_inputs!r}")
        self.name, self.frame_id, self.dof = frame, kin.frame_id(frame), kin.dof
        self.check_inputs = check_inputs
        self.pose, self.jacobian, self.kinematics = _bind(kin, self.frame_id, check_inputs)

    def __repr__(self) -> str:
        return f"<FrameHandle {self.name!r}: {self.dof} dof, check_inputs={self.check_inputs}>"


PoseFunction = Callable[[np.ndarray], np.ndarray]
JacobianFunction = Callable[..., np.ndarray]
KinematicsFunction = Callable[..., tuple[np.ndarray, np.ndarray]]


def _bind(
    kin: Kinematics, fid: int, checking: bool
) -> tuple[PoseFunction, JacobianFunction, KinematicsFunction]:
    """The three closures: ``pose(q)``, ``jacobian(q, reference="local_world_aligned")``,
    ``kinematics(q, reference="local_world_aligned")``."""
    model, coords, dof = kin.model, kin.coordinates, kin.dof
    check, identity = coords.check, coords.identity
    forward, place, frame_jacobian = pin.forwardKinematics, pin.updateFramePlacement, pin.computeFrameJacobian
    local_frame = pin.LOCAL
    references = dict(REFERENCES)
    local = threading.local()

    def state() -> object:
        """This thread's (Data, q_pin buffer): the engine's Data of this thread, a buffer of our own."""
        local.data, local.buffer = kin.data(), np.zeros(coords.nq)
        return local.data

    mimic = kin.mimic
    q_pin = mimic.q_pin_for(model, fid)  # only the mimic joints that move this frame are written

    def pinocchio_q(q: np.ndarray) -> np.ndarray:
        return q_pin(q, local.buffer)

    def resolve(reference: Reference) -> pin.ReferenceFrame:
        try:
            return references[reference]
        except (KeyError, TypeError):
            return resolve_reference(reference)

    if identity:

        def pose(q: np.ndarray) -> np.ndarray:
            if checking:
                q = check(q, allow_batch=False)
            try:
                data = local.data
            except AttributeError:
                data = state()
            forward(model, data, q)
            return place(model, data, fid).homogeneous
    else:

        def pose(q: np.ndarray) -> np.ndarray:
            if checking:
                q = check(q, allow_batch=False)
            try:
                data = local.data
            except AttributeError:
                data = state()
            forward(model, data, pinocchio_q(q))
            return place(model, data, fid).homogeneous

    if dof == 0:  # Pinocchio 4.1 crashes on a frame Jacobian with nv = 0

        def zero_jacobian(q: np.ndarray, reference: Reference = "local_world_aligned") -> np.ndarray:
            resolve(reference)
            if checking:
                check(q, allow_batch=False)
            return np.zeros((6, 0))

        def zero_kinematics(
            q: np.ndarray, reference: Reference = "local_world_aligned"
        ) -> tuple[np.ndarray, np.ndarray]:
            resolve(reference)
            return pose(q), np.zeros((6, 0))

        return pose, zero_jacobian, zero_kinematics

    if identity and dof > 1:

        def plain_jacobian(q: np.ndarray, reference: Reference = "local_world_aligned") -> np.ndarray:
            try:
                ref = references[reference]
            except (KeyError, TypeError):
                ref = resolve_reference(reference)
            if checking:
                q = check(q, allow_batch=False)
            try:
                data = local.data
            except AttributeError:
                data = state()
            return frame_jacobian(model, data, q, fid, ref)

        def plain_kinematics(
            q: np.ndarray, reference: Reference = "local_world_aligned"
        ) -> tuple[np.ndarray, np.ndarray]:
            try:
                ref = references[reference]
            except (KeyError, TypeError):
                ref = resolve_reference(reference)
            if checking:
                q = check(q, allow_batch=False)
            try:
                data = local.data
            except AttributeError:
                data = state()
            if ref == local_frame:  # Pinocchio's LOCAL frame Jacobian does not place the joints
                forward(model, data, q)
                return place(model, data, fid).homogeneous, frame_jacobian(model, data, q, fid, ref)
            J = frame_jacobian(model, data, q, fid, ref)
            return place(model, data, fid).homogeneous, J

        return pose, plain_jacobian, plain_kinematics

    # J_pin · M (only the mimic joints that move this frame); (6,) → (6, 1)
    fold = mimic.folder(model, fid) if not identity else (lambda J: J.reshape(6, -1))

    def jacobian(q: np.ndarray, reference: Reference = "local_world_aligned") -> np.ndarray:
        ref = resolve(reference)
        if checking:
            q = check(q, allow_batch=False)
        try:
            data = local.data
        except AttributeError:
            data = state()
        return fold(frame_jacobian(model, data, q if identity else pinocchio_q(q), fid, ref))

    def kinematics(
        q: np.ndarray, reference: Reference = "local_world_aligned"
    ) -> tuple[np.ndarray, np.ndarray]:
        ref = resolve(reference)
        if checking:
            q = check(q, allow_batch=False)
        try:
            data = local.data
        except AttributeError:
            data = state()
        if not identity:
            q = pinocchio_q(q)
        if ref == local_frame:  # Pinocchio's LOCAL frame Jacobian does not place the joints
            forward(model, data, q)
            return place(model, data, fid).homogeneous, fold(frame_jacobian(model, data, q, fid, ref))
        J = fold(frame_jacobian(model, data, q, fid, ref))
        return place(model, data, fid).homogeneous, J

    return pose, jacobian, kinematics


__all__ = ["FrameHandle"]
