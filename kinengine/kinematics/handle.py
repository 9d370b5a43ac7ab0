"""A frame handle for hot loops: one frame's pose and Jacobian with everything looked up once.

>>> fk = robot.frame("tool0")                  # FrameHandle; check_inputs=False skips the input check
>>> T = fk.pose(q)                             # T_IF (4, 4) [m] in the root link frame I
>>> J = fk.jacobian(q, reference="local")      # (6, dof), rows [linear; angular]
>>> T, J = fk.kinematics(q)                    # both from one pass, equal to the two calls above

Same frames, units and references as :mod:`kinengine.kinematics.engine`. The handle binds the frame's
Pinocchio model (:meth:`Kinematics.frame_path`) and index once; each thread gets its own Data, so one
handle serves several threads. ``check_inputs=True``: every call runs the one input check
(:attr:`CoordinateMap.ready` first, :meth:`CoordinateMap.check` for anything else); ``False``: the caller
promises a finite float64 array (dof,), anything else is undefined behaviour of Pinocchio. ``batches=True``
(the Robot's own handles) also takes batches (N, dof) to the vectorized path. A plain frame's calls are
the C accelerator's (:mod:`kinengine.model.accelerator`) where it runs: the same Pinocchio calls.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin

from ..arrays import Reference
from ..errors import OptionError
from ..model import accelerator
from ..model.coordinates import MAX_MAGNITUDE
from . import batch
from .engine import REFERENCES, Calls, Kinematics, resolve_reference, single_calls, thread_data


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
                raise OptionError(f"`{option}` must be True or False, got {value!r}")
        self.name, self.frame_id, self.dof = frame, kin.frame_id(frame), kin.dof
        self.check_inputs = check_inputs
        self.pose, self.jacobian, self.kinematics, self.placement = _bind(
            kin, self.frame_id, check_inputs, batches
        )

    def __repr__(self) -> str:
        return f"<FrameHandle {self.name!r}: {self.dof} dof, check_inputs={self.check_inputs}>"


def _bind(kin: Kinematics, fid: int, checking: bool, batches: bool) -> tuple[Callable[..., Any], ...]:
    """The closures ``pose(q)``, ``jacobian(q, reference="local_world_aligned")``,
    ``kinematics(q, reference="local_world_aligned")`` and ``placement()``: the engine's single calls behind
    :func:`_checked_calls`; for a plain frame (q as it is, dof > 1) the C accelerator's calls, which hand
    every call that is not plain back to these closures."""
    model, pfid, new_data, mapped = kin.frame_path(fid)
    local, data = thread_data(new_data)  # the C calls read local.data and call data() when it is missing

    def placement() -> tuple[np.ndarray, np.ndarray]:
        frame = data().oMf[pfid]
        rotation, translation = frame.rotation, frame.translation
        rotation.flags.writeable = translation.flags.writeable = False
        return rotation, translation

    calls = _checked_calls(
        kin, fid, single_calls(kin.coordinates, model, pfid, data, mapped), checking, batches
    )
    if mapped or kin.dof <= 1:
        return (*calls, placement)
    native = accelerator.frame_calls(
        dof=kin.dof,
        limit=MAX_MAGNITUDE,
        checking=checking,
        model=model,
        frame_id=pfid,
        local=local,
        state=data,
        forward=pin.forwardKinematics,
        place=pin.updateFramePlacement,
        frame_jacobian=pin.computeFrameJacobian,
        references=dict(REFERENCES),
        default_reference=REFERENCES["local_world_aligned"],
        local_reference=REFERENCES["local"],
        slow_pose=calls[0],
        slow_jacobian=calls[1],
        slow_kinematics=calls[2],
    )  # the same Pinocchio calls in C, which hands these closures every call that is not plain
    return (*(calls if native is None else native), placement)


def _checked_calls(kin: Kinematics, fid: int, single: Calls, checking: bool, batches: bool) -> Calls:
    """The public calls: the reference resolved by name, and with ``checking`` q checked once
    (:attr:`CoordinateMap.ready` first, :meth:`CoordinateMap.check` for anything else); a checked batch
    (N, dof), allowed with ``batches``, goes to :func:`kinengine.kinematics.batch.evaluate`."""
    pose1, jacobian1, kinematics1 = single
    ready, full_check, resolve = kin.coordinates.ready, kin.coordinates.check, resolve_reference

    def pose(q: np.ndarray) -> np.ndarray:
        if checking and not ready(q):
            q = full_check(q, allow_batch=batches)
            if q.ndim == 2:
                return batch.evaluate(kin, q, fid, None, jacobian=False)[0]  # type: ignore[return-value]
        return pose1(q)

    def jacobian(q: np.ndarray, reference: Reference = "local_world_aligned") -> np.ndarray:
        ref = resolve(reference)
        if checking and not ready(q):
            q = full_check(q, allow_batch=batches)
            if q.ndim == 2:
                return batch.evaluate(kin, q, fid, ref, pose=False)[1]  # type: ignore[return-value]
        return jacobian1(q, ref)

    def kinematics(
        q: np.ndarray, reference: Reference = "local_world_aligned"
    ) -> tuple[np.ndarray, np.ndarray]:
        ref = resolve(reference)
        if checking and not ready(q):
            q = full_check(q, allow_batch=batches)
            if q.ndim == 2:
                return batch.evaluate(kin, q, fid, ref)  # type: ignore[return-value]
        return kinematics1(q, ref)

    return pose, jacobian, kinematics


__all__ = ["FrameHandle"]
