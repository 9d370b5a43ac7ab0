"""Differential inverse kinematics as one quadratic program per control step (the velocity-level solver a
controller calls each cycle), solved by DAQP (or ProxQP) through ``qpsolvers``.

>>> ik = kinengine.DifferentialIK(robot, [kinengine.PoseTarget("tool0", T_target),
...                                       kinengine.PostureTarget(robot.neutral(), weight=1e-3)])
>>> qdot = ik.solve(q, dt)           # [rad/s | m/s], (dof,); q += qdot * dt

The step Δq = q̇·dt minimizes

    Σ_targets w_i ‖A_i Δq − k_i e_i‖² + w_p ‖Δq − k_p (q_ref − q)‖² + (λ + μ Σ_i w_i ‖k_i e_i‖²) ‖Δq‖²

subject to max(q_min − q, −q̇_max dt) ≤ Δq ≤ min(q_max − q, q̇_max dt) (joint position limits as velocity
bounds over the step, and joint velocity limits q̇_max from the URDF's ``<limit velocity>``, overridable).
λ (``damping``) is a constant Tikhonov term; μ (``lm_damping``) the Levenberg–Marquardt term that grows
with the error, so the step stays short and well conditioned far from the target and near singularities
and vanishes at convergence (Newton steps there).

A :class:`PoseTarget`'s error e is decoupled: position rows "x", "y", "z" are p_target − p in the root frame
I (in B with ``relative_to`` B), with A = J_v (LOCAL_WORLD_ALIGNED linear rows, or the relative Jacobian's
in B); rotation rows "rx", "ry", "rz" are r = log3(C_Fᵀ C_target), in the frame F's own axes, with
A = Jlog3(C_targetᵀ C_F) · C_Fᵀ J_ω, the exact derivative (d r = −A dq), so a full target converges
quadratically. Rows select a sub-task: ("x", "y", "z", "rx", "ry") leaves the rotation about F's z axis free
(a 5-D target: position plus tool axis). The gain k ∈ (0, 1] is the fraction of the error removed per step
(1: a full Newton step). Units: e in [m] and [rad].
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..errors import OptionError
from ..kinematics.engine import Kinematics
from ..kinematics.memory import create_data
from ..kinematics.relative import relative_terms
from ..urdf.description import RobotDescription
from .constraints import InequalityConstraint, checked_constraints, step_inequalities

ROWS = ("x", "y", "z", "rx", "ry", "rz")
SOLVERS = ("daqp", "proxqp")
_LWA = pin.LOCAL_WORLD_ALIGNED
_BIG = 1e20  # stands for an infinite bound


@dataclass(eq=False)
class PoseTarget:
    """Drive ``frame`` to ``T_target`` (4, 4): its pose in the root frame I, or in ``relative_to`` B.

    rows: a subset of ("x", "y", "z", "rx", "ry", "rz") (module doc: position rows in I or B, rotation rows
    in the frame's own axes); None: all six. gain in (0, 1]: fraction of the error removed per step.
    weight >= 0: its weight in the cost. Assign ``T_target`` between steps to track a moving target.
    """

    frame: str
    T_target: np.ndarray
    rows: Sequence[str] | None = None
    gain: float = 1.0
    weight: float = 1.0
    relative_to: str | None = None


@dataclass(eq=False)
class PostureTarget:
    """Pull q towards ``q_ref`` (dof,) with ``weight`` (a regularization; small, e.g. 1e-3). ``joints``: names
    of the coordinates it acts on (None: all). Give a large weight on a coordinate to lock it there."""

    q_ref: np.ndarray
    weight: float = 1e-3
    gain: float = 1.0
    joints: Sequence[str] | None = None
    _mask: np.ndarray | None = field(default=None, repr=False)


class QPRobot(Protocol):
    """What DifferentialIK reads of the Robot passed in (public attributes of :class:`kinengine.Robot`)."""

    @property
    def engine(self) -> Kinematics: ...

    @property
    def dof(self) -> int: ...

    @property
    def description(self) -> RobotDescription: ...

    @property
    def joint_names(self) -> Sequence[str]: ...

    @property
    def lower_limits(self) -> npt.NDArray[np.float64]: ...

    @property
    def upper_limits(self) -> npt.NDArray[np.float64]: ...

    def frame_id(self, frame: str) -> int: ...


class _PoseTerm:
    """A PoseTarget resolved against the robot: frame ids, row indices, buffers."""

    def __init__(self, robot: QPRobot, target: PoseTarget) -> None:
        self.target = target
        self.fid = robot.frame_id(target.frame)
        self.fb = None if target.relative_to is None else robot.frame_id(target.relative_to)
        rows = ROWS if target.rows is None else tuple(target.rows)
        for r in rows:
            if r not in ROWS:
                raise OptionError(f"PoseTarget rows are among {ROWS}, got {r!r}")
        if len(set(rows)) != len(rows) or not rows:
            raise OptionError(f"PoseTarget rows must be distinct and not empty, got {rows!r}")
        self.rows = np.array([ROWS.index(r) for r in rows], dtype=np.intp)
        self.all_rows = rows == ROWS
        if not (0.0 < target.gain <= 1.0) or not (target.weight >= 0.0 and math.isfinite(target.weight)):
            raise OptionError(
                f"PoseTarget gain must be in (0, 1] and weight finite >= 0, got gain {target.gain!r}, "
                f"weight {target.weight!r}"
            )
        self.A6 = np.zeros((6, robot.dof))
        self.e6 = np.zeros(6)


class DifferentialIK:
    """One QP per control step: see the module doc. Build once, call :meth:`solve` every cycle.

    robot: a kinengine Robot. tasks: PoseTarget and PostureTarget entries. damping λ >= 0 and
    lm_damping μ >= 0 as in the module doc. velocity_limits: None (the URDF's; a joint without one is
    unbounded), an array (dof,) [rad/s | m/s], or a mapping joint name -> limit overriding the URDF's (0
    locks a joint). position_limits: False ignores the joint limits. solver: "daqp" (default) or "proxqp".
    constraints: objects whose ``inequality(robot, q, dt)`` returns (G, h), G q̇ ≤ h, added to the QP
    (:class:`InequalityConstraint`, e.g. :class:`kinengine.CollisionAvoidance`).
    """

    def __init__(
        self,
        robot: QPRobot,
        tasks: Sequence[PoseTarget | PostureTarget],
        *,
        damping: float = 1e-12,
        lm_damping: float = 1e-3,
        velocity_limits: npt.ArrayLike | Mapping[str, float] | None = None,
        position_limits: bool = True,
        solver: str = "daqp",
        constraints: Sequence[InequalityConstraint] = (),
    ) -> None:
        if solver not in SOLVERS:
            raise OptionError(f"solver must be one of {', '.join(SOLVERS)}, got {solver!r}")
        if not (damping >= 0 and lm_damping >= 0):
            raise OptionError(f"damping and lm_damping must be >= 0, got {damping!r}, {lm_damping!r}")
        self.robot, self.solver, self.damping, self.lm_damping = (
            robot,
            solver,
            float(damping),
            float(lm_damping),
        )
        kin = robot.engine
        self._model, self._coords = kin.model, kin.coordinates
        self._data = create_data(self._model, "a DifferentialIK")
        n = self.dof = robot.dof
        self._pose_terms: list[_PoseTerm] = []
        self._postures: list[PostureTarget] = []
        for task in tasks:
            if isinstance(task, PoseTarget):
                self._pose_terms.append(_PoseTerm(robot, task))
            elif isinstance(task, PostureTarget):
                mask = (
                    np.ones(n)
                    if task.joints is None
                    else np.array([1.0 if name in set(task.joints) else 0.0 for name in robot.joint_names])
                )
                unknown = set(task.joints or ()) - set(robot.joint_names)
                if unknown:
                    raise OptionError(
                        f"PostureTarget joints {sorted(unknown)} are not coordinates of the robot; "
                        f"known: {', '.join(robot.joint_names)}"
                    )
                task._mask = mask
                self._postures.append(task)
            else:
                raise OptionError(f"tasks are PoseTarget or PostureTarget entries, got {task!r}")
        if not self._pose_terms and not self._postures:
            raise OptionError("DifferentialIK needs at least one task")
        self.velocity_limits = self._velocity_limits(robot, velocity_limits)
        self._lower = robot.lower_limits if position_limits else np.full(n, -np.inf)
        self._upper = robot.upper_limits if position_limits else np.full(n, np.inf)
        self._H, self._c = np.zeros((n, n)), np.zeros(n)
        self._lb, self._ub = np.zeros(n), np.zeros(n)
        self._diag = self._H.reshape(-1)[:: n + 1]  # a view of H's diagonal
        self._AtA = np.zeros((n, n))
        self.last_error = np.full(6 * len(self._pose_terms), np.nan)
        self.qp_calls = 0
        self.constraints = checked_constraints(constraints)
        """How many solves needed the QP solver (a bound active); the others were one linear solve."""

    @staticmethod
    def _velocity_limits(
        robot: QPRobot, limits: npt.ArrayLike | Mapping[str, float] | None
    ) -> npt.NDArray[np.float64]:
        urdf = {j.name: j.velocity for j in robot.description.joints}
        out = np.array(
            [urdf.get(name) if urdf.get(name) else np.inf for name in robot.joint_names], dtype=float
        )
        if limits is None:
            return out
        if isinstance(limits, Mapping):
            for name, value in limits.items():
                if name not in robot.joint_names:
                    raise OptionError(
                        f"velocity_limits names unknown joint {name!r}; known: {', '.join(robot.joint_names)}"
                    )
                out[robot.joint_names.index(name)] = float(value)
        else:
            out = np.array(limits, dtype=float).reshape(-1)
            if out.shape != (robot.dof,):
                raise OptionError(f"velocity_limits must have shape ({robot.dof},), got {out.shape}")
        if not (out >= 0).all():
            raise OptionError("velocity_limits must be >= 0 (inf for none)")
        return out

    @property
    def tasks(self) -> tuple[PoseTarget | PostureTarget, ...]:
        return tuple(t.target for t in self._pose_terms) + tuple(self._postures)

    def solve(self, q: npt.ArrayLike, dt: float) -> npt.NDArray[np.float64]:
        """q̇ (dof,) [rad/s | m/s] for one step of ``dt`` [s] from q (dof,): q + q̇·dt is the QP's step.

        ``last_error`` then holds each PoseTarget's 6 error rows [p_target − p; log3(C_Fᵀ C_target)] at q
        (before the step), stacked.
        """
        if not dt > 0:
            raise OptionError(f"dt must be > 0 [s], got {dt!r}")
        q = self._coords.check(q, allow_batch=False)
        model, data = self._model, self._data
        qp = q if self._coords.identity else self._coords.to_pinocchio(q)
        if self._pose_terms:
            pin.computeJointJacobians(model, data, qp)
        H, c, diag, AtA = self._H, self._c, self._diag, self._AtA
        H.fill(0.0)
        c.fill(0.0)
        weighted_sq = 0.0
        for k, term in enumerate(self._pose_terms):
            A, e = self._pose_rows(term, model, data)
            self.last_error[6 * k : 6 * k + 6] = e
            target = term.target
            if term.all_rows:
                e *= target.gain
            else:
                A, e = A[term.rows], e[term.rows] * target.gain
            w = target.weight
            np.dot(A.T, A, out=AtA)
            if w != 1.0:
                AtA *= w
                e *= math.sqrt(w)
                A = A * math.sqrt(w)
            H += AtA
            c -= A.T.dot(e)
            weighted_sq += float(e.dot(e))
        for posture in self._postures:
            w, mask = posture.weight, posture._mask
            assert mask is not None  # set by __init__
            e = posture.gain * (np.asarray(posture.q_ref, dtype=float) - q) * mask
            diag += w * mask
            c -= w * e
            weighted_sq += w * float(e.dot(e))
        diag += self.damping + self.lm_damping * weighted_sq
        vmax = self.velocity_limits * dt
        lb, ub = self._lb, self._ub
        np.maximum(self._lower - q, -vmax, out=lb)
        np.minimum(self._upper - q, vmax, out=ub)
        np.maximum(ub, np.minimum(lb, 0.0), out=ub)  # q outside its limits: move back as fast as allowed
        np.minimum(lb, ub, out=lb)
        # H is positive definite: when the unconstrained minimizer −H⁻¹c lies within the bounds it is the
        # QP's solution (no bound active), found by one linear solve; otherwise the QP solver decides.
        G, h = step_inequalities(self.constraints, self.robot, q, dt, self.dof)
        try:
            step = np.linalg.solve(H, -c)
        except np.linalg.LinAlgError:
            step = None
        if (
            step is None
            or not ((step >= lb).all() and (step <= ub).all())
            or (G is not None and not (G @ step <= h).all())
        ):
            self.qp_calls += 1
            import qpsolvers  # only when a bound is active: keeps `import kinengine` light

            step = qpsolvers.solve_qp(
                H, c, G, h, lb=np.clip(lb, -_BIG, _BIG), ub=np.clip(ub, -_BIG, _BIG), solver=self.solver
            )
            if step is None:  # cannot happen for a box QP with H > 0; a safe answer anyway
                step = np.zeros(self.dof)
            np.clip(step, lb, ub, out=step)  # the solver's tolerance (~1e-14) off a bound: onto it
        return np.asarray(step / dt, dtype=np.float64)  # float64 already (H, c are): no copy

    def _pose_rows(
        self, term: _PoseTerm, model: pin.Model, data: pin.Data
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(A (6, dof), e (6,)): rows [position; rotation] of the module doc, at the current Data."""
        fold = self._coords.fold
        MA = pin.updateFramePlacement(model, data, term.fid)
        JA = fold(pin.getFrameJacobian(model, data, term.fid, _LWA).reshape(6, -1))
        T_target = term.target.T_target
        if term.fb is None:
            C, p, Jv, Jw = MA.rotation, MA.translation, JA[:3], JA[3:]
        else:
            MB = pin.updateFramePlacement(model, data, term.fb)
            JB = fold(pin.getFrameJacobian(model, data, term.fb, _LWA).reshape(6, -1))
            inner = relative_terms(MA.homogeneous, JA, MB.homogeneous, JB)
            CB = MB.rotation
            C, p = CB.T @ MA.rotation, CB.T @ (MA.translation - MB.translation)
            Jv, Jw = CB.T @ inner[:3], CB.T @ inner[3:]
        C_target = T_target[:3, :3]
        e, A = term.e6, term.A6
        e[:3] = T_target[:3, 3] - p
        e[3:] = pin.log3(C.T @ C_target)
        A[:3] = Jv
        A[3:] = pin.Jlog3(C_target.T @ C) @ (C.T @ Jw)
        return A, e


__all__ = ["ROWS", "SOLVERS", "DifferentialIK", "PoseTarget", "PostureTarget"]
