"""Differential inverse kinematics: damped least squares with Levenberg–Marquardt damping.

Error (decoupled): e = (p_d − p, log(C_d Cᵀ)) [m, rad] in the root frame I, p and C the frame's position
and orientation in I, so |e_p| is the position error [m] and |e_R| the rotation angle [rad] that the
tolerances are checked against; to first order its Jacobian is J = J_e0 ("local_world_aligned").
With ``rows=`` or ``weights=`` both halves are expressed in the target frame D (e_D = C_dᵀ e, J_D = C_dᵀ J
blockwise) and only the named rows count: rows=("x", "y", "z", "rx", "ry") is a 5-D target, position plus
tool axis (D's z axis): rotation about it is left free. ``weights`` (w ≥ 0, one per kept row) minimize
Σ w_i e_i² instead of |e|²; a full pose minimizes |e_p|² + (ρ|e_R|)², ρ = 0.2 m/rad.
Step, damping, limit weights, nullspace pull and give-way rule: :mod:`.ik_step`; seeds (``q0``, the
stored configurations nearest the target, the middle of the ranges, then ``restarts`` random ones):
:mod:`.ik_seeds`; the attempt loop of one frame or several: :mod:`.ik_solver`; batches: :mod:`.ik_batch`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ..errors import OptionError
from . import ik_target
from .ik_multi import checked_goals
from .ik_seeds import NEAREST_SEEDS, SEED_TABLE_BYTES, SEED_TABLES, frame_seeds
from .ik_solver import IKResult, solve

if TYPE_CHECKING:  # named for the checker only
    from .ik_batch import IKBatchResult
    from .robot_like import RobotLike


def inverse_kinematics(
    robot: RobotLike,
    target: npt.ArrayLike | Mapping[str, npt.ArrayLike],
    frame: str | None = None,
    q0: object = None,
    *,
    position: str | None = None,
    rotation: str | None = None,
    rows: object = None,
    weights: object = None,
    tol_position: float = 1e-6,
    tol_rotation: float = 1e-6,
    max_iterations: int = 100,
    restarts: int = 3,
    rng: np.random.Generator | int | None = None,
    nullspace_target: object = None,
    nullspace_gain: float = 0.1,
    min_damping: float = 1e-6,
    method: str = "auto",
) -> IKResult | IKBatchResult:
    """q (within the limits) that puts ``frame`` (default: end effector) at ``target`` in I.

    ``target``: T_IF (4, 4), a batch (N, 4, 4) (then an :class:`~kinengine.control.ik_batch.IKBatchResult`
    of N results, solved vectorized), or parameters χ = (χ_P, χ_R) of the parameterizations named by
    ``position``/``rotation`` (naming only one solves for that part alone). ``rows``: labels or indices
    of ("x", "y", "z", "rx", "ry", "rz") to keep, in the target's frame; ``weights``: one w ≥ 0 per kept
    row. Success: position error <= ``tol_position`` [m] and rotation error <= ``tol_rotation`` [rad].
    ``max_iterations``: per attempt; ``restarts``: random attempts after the seeded ones (``rng``).
    ``nullspace_target`` (dof,): preferred q, pursued with ``nullspace_gain`` [1/iteration] where the
    task leaves freedom; coordinates that move no target frame are set to it (clipped into the limits).
    ``min_damping``: λ_min [1]. Every option is validated (OptionError).

    Several frames at once: ``target`` a mapping {frame: T_IF (4, 4)} (``frame`` None), ``rows`` and
    ``weights`` one spec for all or a mapping {frame: spec}; see :mod:`kinengine.control.ik_multi`.

    ``method``: "numeric" this solver; "closed_form" the solution nearest ``q0`` (default: the middle of
    the ranges) among every closed-form one (:mod:`kinengine.control.ik_dispatch`); "auto" the closed form
    for a pose target of a chain that has one (and the ``ik`` extra installed), else this solver.
    """
    options = ik_target.Options(
        tol_position, tol_rotation, max_iterations, restarts, nullspace_target, nullspace_gain, min_damping,
        q0 is not None,
    )  # fmt: skip
    generator = ik_target.RandomSource(rng)
    if isinstance(target, Mapping):
        if frame is not None or position is not None or rotation is not None:
            raise OptionError(
                "a mapping {frame: pose} names its frames and takes poses (4, 4): leave `frame`, "
                "`position` and `rotation` None (or pass one pose with frame=...)"
            )
        from .closed_form import METHODS

        if method not in METHODS:
            raise OptionError(f"unknown method {method!r}; use 'auto', 'closed_form' or 'numeric'")
        if method not in ("auto", "numeric"):
            raise OptionError(
                f"method={method!r} does not solve a mapping {{frame: pose}} (closed forms solve poses "
                "(4, 4) or (N, 4, 4) of one frame); use method='numeric' or 'auto'"
            )
        goals = checked_goals(robot, target, rows, weights, options)
        start = ik_target.checked_start(robot, q0, "q0", None)
        return solve(robot, goals, frame_seeds(robot, goals, start), generator, several=True)
    problem = ik_target.checked_problem(robot, frame, rows, weights, options)
    parameters = position is not None or rotation is not None
    if problem.rows is not None and parameters:
        raise OptionError(
            "`rows=` and `weights=` apply to pose targets (4, 4) or (N, 4, 4); for parameters χ "
            "name only the parameterizations you need"
        )

    def numeric(T: npt.ArrayLike, q0: object) -> IKResult | IKBatchResult:
        """The numeric solver on the checked problem: a batch (N, 4, 4) vectorized, else one target."""
        batch = None if parameters else ik_target.batch_targets(T)  # (N, 3), (N, 3, 3)
        start = ik_target.checked_start(robot, q0, "q0", None if batch is None else len(batch[0]))
        if batch is None:
            goals = [ik_target.FrameGoal(problem, *ik_target.single_target(T, position, rotation))]
            return solve(robot, goals, frame_seeds(robot, goals, start), generator)
        from .ik_batch import solve_batch

        return solve_batch(robot, problem, *batch, start, generator)

    if method != "numeric":
        from .ik_dispatch import closed_form_or_none

        plain = not parameters and problem.rows is None and nullspace_target is None
        solved = closed_form_or_none(robot, target, frame, q0, method, plain, numeric)
        if solved is not None:
            return solved
    return numeric(target, q0)


__all__ = ["NEAREST_SEEDS", "SEED_TABLES", "SEED_TABLE_BYTES", "IKResult", "inverse_kinematics"]
