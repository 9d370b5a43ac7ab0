"""A frame handle for hot loops: one frame's pose and Jacobian with everything looked up once.

>>> fk = robot.frame("tool0")                  # FrameHandle; check_inputs=False skips the input check
>>> T = fk.pose(q)                             # T_IF (4, 4) [m] in the root link frame I
>>> J = fk.jacobian(q, reference="local")      # (6, dof), rows [linear; angular]
>>> T, J = fk.kinematics(q)                    # both from one pass, equal to the two calls above

Same frames, units and references as :mod:`kinengine.kinematics.engine`. The handle binds the
frame's Pinocchio model (:meth:`Kinematics.frame_path`), its frame index and Pinocchio's functions
once; each thread gets its own Pinocchio Data (a frame that a mimic joint moves gets a fresh
q_pin = M q + b per call), so one handle serves several threads. With ``check_inputs=True`` every
call runs the one input check: :attr:`CoordinateMap.ready` first (a float64 vector of the right
length and magnitude passes with one scalar test), :meth:`CoordinateMap.check` for anything else
(converted, or refused with a ConfigurationError). With ``check_inputs=False`` the caller promises a
float64 array of shape (dof,) with finite entries; anything else is undefined behaviour of Pinocchio
(wrong numbers or an exception), never checked. ``batches=True`` (the Robot's own handles) also
takes checked batches q (N, dof) to the vectorized batch path. Where the C accelerator runs
(:mod:`kinengine.model.accelerator`), a plain frame's ``pose``, ``jacobian`` and ``kinematics`` are its
C calls, which make the same Pinocchio calls and hand every other call to the closures below.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ..arrays import Reference
from ..model import accelerator
from ..model.coordinates import MAX_MAGNITUDE
from . import batch
from .engine import REFERENCES, Kinematics, resolve_reference


class FrameHandle:
    """Pose and Jacobian of one frame at configurations q (dof,); see the module doc."""

    __slots__ = ("check_inputs", "dof", "frame_id", "jacobian", "kinematics", "name", "placement", "pose")

    pose: Callable[..., np.ndarray]
    jacobian: Callable[..., np.ndarray]
    kinematics: Callable[..., tuple[np.ndarray, np.ndarray]]
    placement: Callable[[], tuple[np.ndarray, np.ndarray]]
    """``placement()``: (C_IF (3, 3), p (3,)) as live read-only views of this thread's Data: they show the
    frame as the last pose/jacobian/kinematics call of this thread placed it (LOCAL Jacobians excepted)."""

    def __init__(
        self, kin: Kinematics, frame: str, *, check_inputs: bool = True, batches: bool = False
    ) -> None:
        for option, value in (("check_inputs", check_inputs), ("batches", batches)):
            if type(value) is not bool:
                from ..errors import OptionError

                raise OptionError(f"`{option}` must be True or False, got {value!r}")
        self.name, self.frame_id, self.dof = frame, kin.frame_id(frame), kin.dof
        self.check_inputs = check_inputs
        self.pose, self.jacobian, self.kinematics, self.placement = _bind(
            kin, self.frame_id, check_inputs, batches
        )

    def __repr__(self) -> str:
        return f"<FrameHandle {self.name!r}: {self.dof} dof, check_inputs={self.check_inputs}>"


PoseFunction = Callable[..., np.ndarray]
JacobianFunction = Callable[..., np.ndarray]
KinematicsFunction = Callable[..., tuple[np.ndarray, np.ndarray]]
PlacementFunction = Callable[[], tuple[np.ndarray, np.ndarray]]


def _bind(
    kin: Kinematics, fid: int, checking: bool, batches: bool
) -> tuple[PoseFunction, JacobianFunction, KinematicsFunction, PlacementFunction]:
    """The closures ``placement()`` and: ``pose(q)``, ``jacobian(q, reference="local_world_aligned")``,
    ``kinematics(q, reference="local_world_aligned")``. A checked q that is a batch (only with ``batches``)
    goes to :func:`kinengine.kinematics.batch.evaluate` on the full model."""
    coords, dof = kin.coordinates, kin.dof
    model, pfid, new_data, mapped = kin.frame_path(fid)
    ready, full_check = coords.ready, coords.check
    forward, place, frame_jacobian = pin.forwardKinematics, pin.updateFramePlacement, pin.computeFrameJacobian
    local_frame = pin.LOCAL
    references = dict(REFERENCES)
    local = threading.local()

    def state() -> pin.Data:
        """This thread's Data of the frame's model."""
        local.data = new_data()
        return local.data

    def check(q: object) -> np.ndarray:
        return full_check(q, allow_batch=batches)

    def placement() -> tuple[np.ndarray, np.ndarray]:
        try:
            data = local.data
        except AttributeError:
            data = state()
        frame = data.oMf[pfid]
        rotation, translation = frame.rotation, frame.translation
        rotation.flags.writeable = translation.flags.writeable = False
        return rotation, translation

    def resolve(reference: Reference) -> pin.ReferenceFrame:
        try:
            return references[reference]
        except (KeyError, TypeError):
            return resolve_reference(reference)

    def batch_pose(Q: np.ndarray) -> np.ndarray:
        return batch.evaluate(kin, Q, fid, None, jacobian=False)[0]  # type: ignore[return-value]

    def batch_jacobian(Q: np.ndarray, ref: pin.ReferenceFrame) -> np.ndarray:
        return batch.evaluate(kin, Q, fid, ref, pose=False)[1]  # type: ignore[return-value]

    def batch_kinematics(Q: np.ndarray, ref: pin.ReferenceFrame) -> tuple[np.ndarray, np.ndarray]:
        return batch.evaluate(kin, Q, fid, ref)  # type: ignore[return-value]

    if dof == 0:  # Pinocchio 4.1 crashes on a frame Jacobian with nv = 0
        zeros = np.zeros((6, 0))

        def pose0(q: np.ndarray) -> np.ndarray:
            if checking:
                q = check(q)
                if q.ndim == 2:
                    return batch_pose(q)
            forward(model, kin.data(), q)
            return place(model, kin.data(), pfid).homogeneous

        def jacobian0(q: np.ndarray, reference: Reference = "local_world_aligned") -> np.ndarray:
            ref = resolve(reference)
            if checking:
                q = check(q)
                if q.ndim == 2:
                    return batch_jacobian(q, ref)
            return zeros.copy()

        def kinematics0(
            q: np.ndarray, reference: Reference = "local_world_aligned"
        ) -> tuple[np.ndarray, np.ndarray]:
            ref = resolve(reference)
            if checking:
                q = check(q)
                if q.ndim == 2:
                    return batch_kinematics(q, ref)
            return pose0(q), zeros.copy()

        return pose0, jacobian0, kinematics0, placement

    if not mapped and dof > 1:  # q and J as they are: the hot path of nearly every robot and frame

        def pose(q: np.ndarray) -> np.ndarray:
            if checking and not ready(q):
                q = check(q)
                if q.ndim == 2:
                    return batch_pose(q)
            try:
                data = local.data
            except AttributeError:
                data = state()
            forward(model, data, q)
            return place(model, data, pfid).homogeneous

        def jacobian(q: np.ndarray, reference: Reference = "local_world_aligned") -> np.ndarray:
            try:
                ref = references[reference]
            except (KeyError, TypeError):
                ref = resolve_reference(reference)
            if checking and not ready(q):
                q = check(q)
                if q.ndim == 2:
                    return batch_jacobian(q, ref)
            try:
                data = local.data
            except AttributeError:
                data = state()
            return frame_jacobian(model, data, q, pfid, ref)

        def kinematics(
            q: np.ndarray, reference: Reference = "local_world_aligned"
        ) -> tuple[np.ndarray, np.ndarray]:
            try:
                ref = references[reference]
            except (KeyError, TypeError):
                ref = resolve_reference(reference)
            if checking and not ready(q):
                q = check(q)
                if q.ndim == 2:
                    return batch_kinematics(q, ref)
            try:
                data = local.data
            except AttributeError:
                data = state()
            if ref == local_frame:  # Pinocchio's LOCAL frame Jacobian does not place the joints
                forward(model, data, q)
                return place(model, data, pfid).homogeneous, frame_jacobian(model, data, q, pfid, ref)
            J = frame_jacobian(model, data, q, pfid, ref)
            return place(model, data, pfid).homogeneous, J

        native = accelerator.frame_calls(
            dof=dof,
            limit=MAX_MAGNITUDE,
            checking=checking,
            model=model,
            frame_id=pfid,
            local=local,
            state=state,
            forward=forward,
            place=place,
            frame_jacobian=frame_jacobian,
            references=references,
            default_reference=references["local_world_aligned"],
            local_reference=references["local"],
            slow_pose=pose,
            slow_jacobian=jacobian,
            slow_kinematics=kinematics,
        )  # the same calls in C, which hands these closures every call that is not plain
        if native is not None:
            return (*native, placement)
        return pose, jacobian, kinematics, placement

    # A frame moved by mimic joints (q_pin = M q + b for those joints only; J_pin · M), or dof == 1
    # (eigenpy returns a (6, 1) Jacobian as (6,)).
    pinocchio_q = kin.mimic.gather() if mapped else (lambda q: q)
    fold = kin.mimic.folder() if mapped else (lambda J: J.reshape(6, -1))

    def mapped_pose(q: np.ndarray) -> np.ndarray:
        if checking and not ready(q):
            q = check(q)
            if q.ndim == 2:
                return batch_pose(q)
        try:
            data = local.data
        except AttributeError:
            data = state()
        forward(model, data, pinocchio_q(q))
        return place(model, data, pfid).homogeneous

    def mapped_jacobian(q: np.ndarray, reference: Reference = "local_world_aligned") -> np.ndarray:
        ref = resolve(reference)
        if checking and not ready(q):
            q = check(q)
            if q.ndim == 2:
                return batch_jacobian(q, ref)
        try:
            data = local.data
        except AttributeError:
            data = state()
        return fold(frame_jacobian(model, data, pinocchio_q(q), pfid, ref))

    def mapped_kinematics(
        q: np.ndarray, reference: Reference = "local_world_aligned"
    ) -> tuple[np.ndarray, np.ndarray]:
        ref = resolve(reference)
        if checking and not ready(q):
            q = check(q)
            if q.ndim == 2:
                return batch_kinematics(q, ref)
        try:
            data = local.data
        except AttributeError:
            data = state()
        q = pinocchio_q(q)
        if ref == local_frame:  # Pinocchio's LOCAL frame Jacobian does not place the joints
            forward(model, data, q)
            return place(model, data, pfid).homogeneous, fold(frame_jacobian(model, data, q, pfid, ref))
        J = fold(frame_jacobian(model, data, q, pfid, ref))
        return place(model, data, pfid).homogeneous, J

    return mapped_pose, mapped_jacobian, mapped_kinematics, placement


__all__ = ["FrameHandle"]
