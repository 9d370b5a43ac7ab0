"""Differential inverse kinematics as one quadratic program per control step (the velocity-level solver a
controller calls each cycle), solved by DAQP (or ProxQP) through ``qpsolvers``. See docs/controller.md.

>>> ik = kinengine.DifferentialIK(robot, [kinengine.PoseTarget("tool0", T_target),
...                                       kinengine.PostureTarget(robot.neutral(), weight=1e-3)])
>>> qdot = ik.solve(q, dt)           # [rad/s | m/s], (dof,); q += qdot * dt

The step Δq = q̇·dt of one priority level minimizes

    Σ_i w_i ‖A_i Δq − (k_i e_i + V_i dt)‖² + w_p ‖Δq − k_p (q_ref − q)‖² + (λ + μ Σ_i w_i ‖k_i e_i‖²) ‖Δq‖²

subject to lb ≤ Δq ≤ ub (joint position limits over the step, velocity limits q̇_max, optional acceleration
limits around the previous q̇) and G q̇ ≤ h (:class:`VelocityConstraint`). λ (``damping``) is a constant
Tikhonov term, μ (``lm_damping``) a Levenberg–Marquardt term growing with the error. A :class:`PoseTarget`'s
error e [m, rad]: position rows "x", "y", "z" p_target − p in the root frame I (in B with ``relative_to``
B), A = J_v; rotation rows "rx", "ry", "rz" r = log3(C_Fᵀ C_target) in the frame F's axes,
A = Jlog3(C_Fᵀ C_target) · C_targetᵀ J_ω (d r = −A dq). The gain k ∈ (0, 1] is the fraction of the error
removed per step. Feed-forward: a target twist [v; ω] in I's axes ("local_world_aligned"; B's with
``relative_to``) gives V = v on the position rows and Jlog3(C_Fᵀ C_target) C_targetᵀ ω on the rotation rows.

Priorities: ``DifferentialIK(robot, level_1, level_2, ...)``: each level after the first is solved only in the
null space of the stacked A of the levels above (an orthonormal basis from their SVD, singular values at or
below ``1e-9·max(1, σ_max)`` count as zero), so a lower level never changes what a higher one achieved.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Literal, overload

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..errors import OptionError
from ..kinematics.memory import create_data
from .qp_levels import Hierarchy, LevelTerms, Limits, step_bounds
from .qp_status import DiffIKStatus, StallWarning, StatusMonitor, checked_window
from .qp_targets import (
    ROWS,
    Level,
    PoseTarget,
    PostureTarget,
    VelocityConstraint,
    number_option,
    stacked_inequalities,
)
from .rate_limits import checked_rate_limits, urdf_velocity_limits
from .robot_like import RobotLike

SOLVERS = ("daqp", "proxqp")
LIMIT_MODES = ("clip", "scale")


class DifferentialIK:
    """One QP per control step (per priority level): see the module doc. Build once, call :meth:`solve`
    every cycle.

    robot: a kinengine Robot. tasks: PoseTarget and PostureTarget entries (the first priority level);
    ``*lower_levels``: further lists, each solved only in the null space of the levels before it.
    damping λ >= 0 and lm_damping μ >= 0 as in the module doc. velocity_limits: None (the URDF's; a joint
    without one is unbounded), an array (dof,) [rad/s | m/s], or a mapping joint name -> limit overriding
    the URDF's (0 locks a joint). acceleration_limits: None (none), an array (dof,) or a mapping name -> limit
    [rad/s² | m/s²] (> 0, inf for none): |q̇ − q̇_prev| <= a·dt, with q̇_prev the q̇ this solver returned last
    (zero after construction or :meth:`reset`) or ``solve(..., previous_qdot=...)``; the velocity bound from
    each position limit then also lets the joint brake in time (q̇²/(2a) + q̇·dt <= q_max − q).
    position_limits: False ignores the joint limits. limits: "clip" (the QP: each bound cuts its own
    coordinate, which may turn the Cartesian direction) or "scale" (the unconstrained step times the largest
    s <= 1 that satisfies every bound: the direction is kept; "clip" when no such s exists). solver: "daqp"
    (default) or "proxqp". constraints: :class:`VelocityConstraint` blocks G q̇ ≤ h. stall_window (steps),
    stall_decrease (relative) and stall_residual: the stall test of :class:`DiffIKStatus`; warn_on_stall:
    warn (:class:`StallWarning`) the first time a step stalls after construction or :meth:`reset`.
    """

    def __init__(
        self,
        robot: RobotLike,
        tasks: Sequence[PoseTarget | PostureTarget],
        *lower_levels: Sequence[PoseTarget | PostureTarget],
        damping: float = 1e-12,
        lm_damping: float = 1e-3,
        velocity_limits: npt.ArrayLike | Mapping[str, float] | None = None,
        acceleration_limits: npt.ArrayLike | Mapping[str, float] | None = None,
        position_limits: bool = True,
        limits: str = "clip",
        solver: str = "daqp",
        constraints: Sequence[VelocityConstraint] = (),
        stall_window: int = 100,
        stall_decrease: float = 1e-3,
        stall_residual: float = 1e-4,
        warn_on_stall: bool = False,
    ) -> None:
        if solver not in SOLVERS:
            raise OptionError(f"solver must be one of {', '.join(SOLVERS)}, got {solver!r}")
        if limits not in LIMIT_MODES:
            raise OptionError(f"limits must be one of {', '.join(LIMIT_MODES)}, got {limits!r}")
        self.damping = number_option("damping", damping)
        self.lm_damping = number_option("lm_damping", lm_damping)
        self.stall_window = checked_window(stall_window)
        self.stall_decrease = number_option("stall_decrease", stall_decrease, 0.0, 1.0)
        self.stall_residual = number_option("stall_residual", stall_residual)
        self.warn_on_stall, self.limits = bool(warn_on_stall), limits
        self.robot, self.solver = robot, solver
        kin = robot.engine
        self._model, self._coords = kin.model, kin.coordinates
        self._data = create_data(self._model, "a DifferentialIK")
        n = self.dof = robot.dof
        self._levels = [Level(robot, level, i) for i, level in enumerate((tasks, *lower_levels))]
        if not any(level.poses or level.postures for level in self._levels):
            raise OptionError("DifferentialIK needs at least one task")
        self._pose_terms = [t for level in self._levels for t in level.poses]
        self._postures = [p for level in self._levels for p in level.postures]
        self.velocity_limits = checked_rate_limits(
            robot, velocity_limits, urdf_velocity_limits(robot), "velocity_limits"
        )
        self.acceleration_limits = checked_rate_limits(
            robot, acceleration_limits, np.full(n, np.inf), "acceleration_limits"
        )
        if acceleration_limits is not None and not (self.acceleration_limits > 0).all():
            raise OptionError("acceleration_limits must be > 0 (inf for none)")
        self._limits = Limits(
            robot.lower_limits if position_limits else np.full(n, -np.inf),
            robot.upper_limits if position_limits else np.full(n, np.inf),
            self.velocity_limits,
            self.acceleration_limits,
        )
        self._hierarchy = Hierarchy(solver)
        self._scale = limits == "scale"
        self._lb, self._ub = np.zeros(n), np.zeros(n)
        self._no_G, self._no_h = np.zeros((0, n)), np.zeros(0)
        self._constraints: list[VelocityConstraint] = []
        for constraint in constraints:
            self.add_constraint(constraint)
        self.last_error = np.full(6 * len(self._pose_terms), np.nan)
        self.reset()

    # -- state ------------------------------------------------------------------------------------
    def reset(self, qdot: npt.ArrayLike | None = None) -> None:
        """Start a new episode: the previous q̇ of the acceleration limits becomes ``qdot`` (default zero:
        at rest), the stall history is cleared and the stall warning may be given again."""
        self._qdot = (
            np.zeros(self.dof)
            if qdot is None
            else self._coords.check(qdot, name="qdot", allow_batch=False).copy()
        )
        self._monitor = StatusMonitor(
            self.robot.joint_names,
            self.stall_window,
            self.stall_decrease,
            self.stall_residual,
            self.warn_on_stall,
        )
        self._monitor.lower, self._monitor.upper = self._limits.lower, self._limits.upper

    @property
    def status(self) -> DiffIKStatus:
        """The :class:`DiffIKStatus` of the last :meth:`solve`."""
        return self._monitor.status

    def add_constraint(self, constraint: VelocityConstraint) -> None:
        """Plug in an extra block G q̇ ≤ h (:class:`VelocityConstraint`), evaluated at every solve."""
        if not callable(getattr(constraint, "inequalities", None)):
            raise OptionError(
                "a constraint needs a method inequalities(robot, q, dt) -> (G, h) or None, got "
                f"{constraint!r:.60}"
            )
        self._constraints.append(constraint)

    @property
    def qp_calls(self) -> int:
        """How many solves needed the QP solver (a bound active); the others were one linear solve."""
        return self._hierarchy.qp_calls

    @property
    def tasks(self) -> tuple[PoseTarget | PostureTarget, ...]:
        """Every task of every level, the pose targets first."""
        return tuple(t.target for t in self._pose_terms) + tuple(self._postures)

    @property
    def levels(self) -> tuple[tuple[PoseTarget | PostureTarget, ...], ...]:
        """The tasks of each priority level, highest first."""
        return tuple(tuple(t.target for t in lv.poses) + tuple(lv.postures) for lv in self._levels)

    # -- the step ---------------------------------------------------------------------------------
    @overload
    def solve(
        self,
        q: npt.ArrayLike,
        dt: float,
        *,
        info: Literal[False] = ...,
        previous_qdot: npt.ArrayLike | None = ...,
    ) -> npt.NDArray[np.float64]: ...
    @overload
    def solve(
        self, q: npt.ArrayLike, dt: float, *, info: Literal[True], previous_qdot: npt.ArrayLike | None = ...
    ) -> tuple[npt.NDArray[np.float64], DiffIKStatus]: ...

    def solve(
        self, q: npt.ArrayLike, dt: float, *, info: bool = False, previous_qdot: npt.ArrayLike | None = None
    ) -> npt.NDArray[np.float64] | tuple[npt.NDArray[np.float64], DiffIKStatus]:
        """q̇ (dof,) [rad/s | m/s] for one step of ``dt`` [s] from q (dof,): q + q̇·dt is the QP's step.

        ``last_error`` then holds each PoseTarget's 6 error rows [p_target − p; log3(C_Fᵀ C_target)] at q
        (before the step), stacked; ``status`` the :class:`DiffIKStatus` (returned too with ``info=True``).
        ``previous_qdot``: the q̇ the acceleration limits start from (default: the last one returned).
        """
        dt = number_option("dt [s]", dt, 0.0, 1e6, open_low=True)
        q = self._coords.check(q, allow_batch=False)
        if previous_qdot is not None:
            self._qdot = self._coords.check(previous_qdot, name="previous_qdot", allow_batch=False).copy()
        model, data, n = self._model, self._data, self.dof
        qp = self._coords.to_pinocchio(q)  # q itself without mimic joints
        if self._pose_terms:
            if n:
                pin.computeJointJacobians(model, data, qp)
            else:  # Pinocchio's frame Jacobian crashes at nv = 0: the poses only
                pin.forwardKinematics(model, data, qp)
        # each level: (H, c, A rows or None) with the cost ½ΔqᵀHΔq + cᵀΔq, its damping included
        residual_sq, offset = 0.0, 0
        terms: list[LevelTerms] = []
        for level in self._levels:
            H, c, A, level_sq = self._level_terms(level, q, dt, offset, level is not self._levels[-1])
            terms.append((H, c, A))
            residual_sq += level_sq
            offset += len(level.poses)
        lb, ub = step_bounds(self._limits, q, dt, self._qdot, self._lb, self._ub)
        G, h = stacked_inequalities(self._constraints, self.robot, q, dt, self._no_G, self._no_h)
        if n == 0:
            step, status, scale = np.zeros(0), "unconstrained", 1.0
        else:
            step, status, scale = self._hierarchy.solve(terms, lb, ub, G, h, self._scale)
        qdot = np.asarray(step / dt, dtype=np.float64)
        if self._limits.has_acceleration:  # the next step's acceleration bounds start from it
            self._qdot = qdot.copy()
        monitor = self._monitor
        monitor.record(status, scale, step, lb, ub, G, h, math.sqrt(residual_sq), q)
        return (qdot, monitor.status) if info else qdot

    def _level_terms(
        self, level: Level, q: np.ndarray, dt: float, offset: int, stack: bool
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, float]:
        """(H, c, A rows or None, ‖e‖²): the level's cost ½ΔqᵀHΔq + cᵀΔq with its damping, its task rows
        if ``stack`` (None for the last level: no lower level needs its null space) and the squared residual
        of its pose rows."""
        n = self.dof
        H, c, diag, AtA, Atb = level.H, level.c, level.diag, level.AtA, level.Atb
        fresh = True  # H and c hold the last step's values until the first term writes them
        weighted_sq = residual_sq = on_diagonal = 0.0
        rows: list[np.ndarray] = []
        for k, term in enumerate(level.poses):
            p, C, twist, gain, w = term.checked()
            A, e, ff = term.rows_at(self._model, self._data, self._coords.fold, p, C, twist)
            self.last_error[6 * (offset + k) : 6 * (offset + k) + 6] = e
            if not term.all_rows:
                A, e, ff = A[term.rows], e[term.rows], ff[term.rows]
            e_sq = float(e @ e)
            residual_sq += e_sq
            weighted_sq += w * gain * gain * e_sq
            if gain != 1.0:
                e *= gain
            b = e + ff * dt if twist is not None else e
            if stack:
                rows.append(A.copy())
            if n:  # H (+)= w AᵀA and c (−)= w Aᵀb: the level's first term writes them, the next ones add
                to_H, to_c = (H, c) if fresh else (AtA, Atb)
                np.dot(A.T, A, out=to_H)
                np.dot(A.T, b, out=to_c)
                if w != 1.0:
                    to_H *= w
                to_c *= -w
                if not fresh:
                    H += AtA
                    c += Atb
                fresh = False
        if fresh:
            H.fill(0.0)
            c.fill(0.0)
        for posture in level.postures:
            mask = posture._mask
            assert mask is not None  # set by Level
            q_ref = self._coords.check(posture.q_ref, name="PostureTarget q_ref", allow_batch=False)
            w = number_option("PostureTarget weight", posture.weight)
            gain = number_option("PostureTarget gain", posture.gain, 0.0, 1.0, open_low=True)
            e = q_ref - q
            if gain != 1.0:
                e *= gain
            if posture._partial:
                e *= mask
                diag += w * mask
            else:
                on_diagonal += w
            weighted_sq += w * float(e @ e)
            c -= w * e
            if stack:
                rows.append(np.eye(n)[mask > 0])
        diag += on_diagonal + self.damping + self.lm_damping * weighted_sq
        A_rows = (np.vstack(rows) if rows else np.zeros((0, n))) if stack else None
        return H, c, A_rows, residual_sq


__all__ = [
    "LIMIT_MODES",
    "ROWS",
    "SOLVERS",
    "DiffIKStatus",
    "DifferentialIK",
    "PoseTarget",
    "PostureTarget",
    "StallWarning",
    "VelocityConstraint",
]
