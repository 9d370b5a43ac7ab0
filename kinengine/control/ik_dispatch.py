"""inverse_kinematics' choice of solver (``method=``) and the closed form's answer as an IKResult.

"auto" (the default) takes the closed form (:mod:`kinengine.control.closed_form`) for a plain pose target
(4, 4) or (N, 4, 4) — no rows=, weights=, position=/rotation= or nullspace_target= — when the ``ik`` extra
is installed and the frame's chain has a decomposition, else the numeric solver; "closed_form" raises
where "auto" falls back; "numeric" is the damped least-squares solver of :mod:`kinengine.control.ik`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ..errors import KinematicsError, OptionError
from .closed_form import METHODS, ClosedFormChain, available, chain_of, ik_solutions
from .ik_candidates import residuals
from .ik_ranges import wrap_pi
from .ik_seeds import middle_of_ranges
from .ik_target import checked_start

if TYPE_CHECKING:  # the facade is a higher layer: named for the checker only
    from .ik_batch import IKBatchResult
    from .ik_solver import IKResult
    from .robot_like import RobotLike


def closed_form_or_none(
    robot: RobotLike,
    target: npt.ArrayLike,
    frame: str | None,
    q0: object,
    method: str,
    plain: bool,
    numeric: Callable[[npt.ArrayLike, object], IKResult | IKBatchResult],
) -> IKResult | IKBatchResult | None:
    """inverse_kinematics' dispatch: the closed-form answer nearest q0 (or the middle of the ranges) as an
    IKResult / IKBatchResult, or None for the numeric solver. ``plain``: a pose target without
    rows/weights/parameterizations/null-space preference (what the closed form answers). "auto" takes the
    closed form when the library is installed and the chain has one; poses without a solution go to
    ``numeric(T, q0)``. "closed_form" raises (KinematicsError) where "auto" falls back."""
    if method not in METHODS:
        raise OptionError(f"unknown method {method!r}; use 'auto', 'closed_form' or 'numeric'")
    if method == "numeric":
        return None
    shape = _shape(target) if plain else ()
    plain = len(shape) in (2, 3) and shape[-2:] == (4, 4)
    if method == "auto" and (not plain or not available()):
        return None
    if not plain:
        raise OptionError(
            "method='closed_form' solves pose targets (4, 4) or (N, 4, 4) of one frame without rows=, "
            "weights=, position=/rotation= or nullspace_target=; use method='numeric'"
        )
    if method == "auto":
        chain = chain_of(robot, frame)
        if isinstance(chain, KinematicsError):
            return None
    return nearest_result(robot, target, frame, q0, numeric, fall_back=method == "auto")


def _shape(target: npt.ArrayLike) -> tuple[int, ...]:
    """The target's shape, () for what is no array (the numeric path reports it)."""
    try:
        return tuple(np.shape(target))
    except (TypeError, ValueError):
        return ()


def nearest_result(
    robot: RobotLike,
    target: npt.ArrayLike,
    frame: str | None,
    q0: object,
    numeric: Callable[[npt.ArrayLike, object], IKResult | IKBatchResult] | None,
    fall_back: bool,
) -> IKResult | IKBatchResult:
    """inverse_kinematics' closed-form answer: the solution nearest q0 (default: the middle of the joint
    ranges, zero where a range is unbounded) as an IKResult (pose (4, 4)) or IKBatchResult (N, 4, 4).
    Poses without a solution within the limits: ``numeric(T, q0)`` when ``fall_back``, else
    success False at the reference q, with the errors of the reference q's pose."""
    from .ik_batch import IKBatchResult
    from .ik_solver import IKResult

    single = np.ndim(target) == 2
    start = checked_start(robot, q0, "q0", None if single else np.shape(target)[0])
    reference = middle_of_ranges(robot) if start is None else start
    found = ik_solutions(robot, target, frame, q_near=reference)
    poses = np.asarray(target, dtype=np.float64)
    if single and found.count:  # the common case, without the batch's arrays
        q = _turned_near(robot, found.frame, found.q[0].copy(), reference)
        err_p, err_r = residuals(robot, found.frame, q[None], poses[None])
        return IKResult(q, True, 0, float(err_p[0]), float(err_r[0]), 0)
    batch = poses if not single else poses[None]
    count = np.atleast_1d(np.asarray(found.count))
    solved = count > 0
    q = np.repeat(reference[None], len(batch), axis=0) if reference.ndim == 1 else reference.copy()
    if found.q.size:
        q[solved] = _turned_near(
            robot, found.frame, (found.q[None] if single else found.q)[solved, 0], q[solved]
        )
    err_p, err_r = residuals(robot, found.frame, q, batch)  # unsolved rows: measured at the reference q
    zero = np.zeros(len(batch), dtype=np.intp)
    result = IKBatchResult(q, solved, zero, err_p, err_r, zero.copy())
    missing = np.flatnonzero(~solved)
    if fall_back and numeric is not None and len(missing):
        if single:
            return numeric(poses, q0)
        start = None if q0 is None else q[missing]
        rest = numeric(batch[missing], start)
        for name in ("q", "success", "iterations", "position_error", "rotation_error", "restarts"):
            getattr(result, name)[missing] = getattr(rest, name)
    return result[0] if single else result


def _turned_near(robot: RobotLike, frame: str, q: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """q (dof,) or (N, dof) with each continuous joint of ``frame``'s closed-form chain on the turn nearest
    ``reference`` (ik_solutions reports it in (−π, π]; the answer nearest q0 is q0's own turn of it)."""
    chain = chain_of(robot, frame)
    turn = chain.columns[chain.continuous] if isinstance(chain, ClosedFormChain) else []
    if len(turn):
        q[..., turn] = reference[..., turn] + wrap_pi(q[..., turn] - reference[..., turn])
    return q


__all__ = ["closed_form_or_none", "nearest_result"]
