"""Differential inverse kinematics as one quadratic program per control step (the velocity-level solver a
controller calls each cycle), solved by DAQP (or ProxQP) through ``qpsolvers``.

>>> ik = kinengine.DifferentialIK(robot, [kinengine.PoseTarget("tool0", T_target),
...                                       kinengine.PostureTarget(robot.neutral(), weight=1e-3)])
>>> qdot = ik.solve(q, dt)           # [rad/s | m/s], (dof,); q += qdot * dt

The step Δq = q̇·dt of one priority level minimizes

    Σ_targets w_i ‖A_i Δq − (k_i e_i + V_i dt)‖² + w_p ‖Δq − k_p (q_ref − q)‖² + (λ + μ Σ_i w_i ‖k_i e_i‖²) ‖Δq‖²

subject to lb ≤ Δq ≤ ub (joint position limits as bounds over the step, joint velocity limits q̇_max from
the URDF's ``<limit velocity>``, optional acceleration limits around the previous q̇) and any extra linear
inequality block G q̇ ≤ h (:class:`VelocityConstraint`). λ (``damping``) is a constant Tikhonov term; μ
(``lm_damping``) the Levenberg–Marquardt term that grows with the error, so the step stays short and well
conditioned far from the target and near singularities and vanishes at convergence (Newton steps there).

A :class:`PoseTarget`'s error e is decoupled: position rows "x", "y", "z" are p_target − p in the root frame
I (in B with ``relative_to`` B), with A = J_v (LOCAL_WORLD_ALIGNED linear rows, or the relative Jacobian's
in B); rotation rows "rx", "ry", "rz" are r = log3(C_Fᵀ C_target), in the frame F's own axes, with
A = Jlog3(C_Fᵀ C_target) · C_targetᵀ J_ω, the exact derivative (d r = −A dq), so a full target converges
quadratically. Rows select a sub-task: ("x", "y", "z", "rx", "ry") leaves the rotation about F's z axis free
(a 5-D target: position plus tool axis). The gain k ∈ (0, 1] is the fraction of the error removed per step
(1: a full Newton step). Units: e in [m] and [rad].

Feed-forward: a target's twist [v; ω] (``PoseTarget.twist``) is the velocity of the target's origin and its
angular velocity, both in I's axes (in B's, relative to B, with ``relative_to`` B) — the convention of
``robot.jacobian(q, frame)`` ("local_world_aligned"). It adds V dt to the wanted change of e: V = v on
the position rows, Jlog3(C_Fᵀ C_target) C_targetᵀ ω on the rotation rows (the rate of r while the target
turns), so a target moving at a known twist is followed without the lag e = V dt / k of a pure feedback.

Priorities: ``DifferentialIK(robot, level_1, level_2, ...)``. Each level is solved as a QP with the bounds,
then the next one only in the null space of every higher level's task rows: Δq = Δq_1 + Z z, Z an
orthonormal basis of the null space of the stacked A of the levels above (SVD, singular values at or below
``1e-9·max(1, σ_max)`` count as zero), so a lower level can never change what a higher one achieved, and
the bounds still hold. See docs/controller.md.
"""

from __future__ import annotations

import math
import warnings
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Literal, Protocol, overload

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..errors import KinematicsError, OptionError
from ..kinematics.engine import Kinematics
from ..kinematics.memory import create_data
from ..kinematics.relative import relative_terms
from ..urdf.description import RobotDescription
from .ik_target import single_target

ROWS = ("x", "y", "z", "rx", "ry", "rz")
SOLVERS = ("daqp", "proxqp")
LIMIT_MODES = ("clip", "scale")
_LWA = pin.LOCAL_WORLD_ALIGNED
_BIG = 1e20  # stands for an infinite bound
_NULL_TOL = 1e-9  # relative singular value at or below which a direction is in a level's null space
_ACTIVE_TOL = 1e-12  # [rad | m] a step this close to a bound has it active


def _number(what: str, value: object, low: float = 0.0, high: float = math.inf, open_low: bool = False) -> float:
    """A finite real number in [low, high] ((low, high] with open_low), else OptionError naming ``what``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise OptionError(f"{what} must be a number, got {value!r:.60}")
    x = float(value)
    if not (math.isfinite(x) and (x > low if open_low else x >= low) and x <= high):
        bound = f"({low:g}, {high:g}]" if open_low else f"[{low:g}, {high:g}]"
        raise OptionError(f"{what} must be a finite number in {bound}, got {value!r:.60}")
    return x


@dataclass(eq=False)
class PoseTarget:
    """Drive ``frame`` to ``T_target`` (4, 4): its pose in the root frame I, or in ``relative_to`` B.

    rows: a subset of ("x", "y", "z", "rx", "ry", "rz") (module doc: position rows in I or B, rotation rows
    in the frame's own axes); None: all six. gain in (0, 1]: fraction of the error removed per step.
    weight >= 0: its weight in the cost (w = cost² in pink's and mink's convention: give ``cost=`` instead
    to use theirs). twist: None or the target's twist [v; ω] (6,) [m/s, rad/s] in I's axes (B's with
    ``relative_to``), added as feed-forward. Assign ``T_target`` (and ``twist``) between steps to track a
    moving target; they are checked at every step.
    """

    frame: str
    T_target: np.ndarray
    rows: Sequence[str] | None = None
    gain: float = 1.0
    weight: float = 1.0
    relative_to: str | None = None
    twist: npt.ArrayLike | None = None
    cost: float | None = None

    def __post_init__(self) -> None:
        if self.cost is not None:
            self.weight = _number("PoseTarget cost", self.cost) ** 2


@dataclass(eq=False)
class PostureTarget:
    """Pull q towards ``q_ref`` (dof,) with ``weight`` (a regularization; small, e.g. 1e-3; or ``cost=`` c in
    pink's and mink's convention, weight = c²). ``joints``: names of the coordinates it acts on (None: all).
    Give a large weight on a coordinate to lock it there, or put it on a lower priority level."""

    q_ref: np.ndarray
    weight: float = 1e-3
    gain: float = 1.0
    joints: Sequence[str] | None = None
    _mask: np.ndarray | None = field(default=None, repr=False)
    cost: float | None = None

    def __post_init__(self) -> None:
        if self.cost is not None:
            self.weight = _number("PostureTarget cost", self.cost) ** 2


class VelocityConstraint(Protocol):
    """An extra block of linear inequalities on q̇ that another module plugs into :class:`DifferentialIK`
    (``constraints=[...]`` or :meth:`DifferentialIK.add_constraint`): a collision constraint, a workspace
    wall, a velocity damper.

    ``inequalities(q, dt)`` is called once per :meth:`DifferentialIK.solve` at the checked q (dof,) and
    returns (G (m, dof), h (m,)) meaning G q̇ ≤ h, q̇ in [rad/s | m/s] and h in G's row units per second
    (e.g. [m/s] for a distance rate), or None when nothing constrains this step. Every priority level and
    ``limits="scale"`` respect it; ``status.active_constraints`` says which rows bind.
    """

    def inequalities(
        self, q: npt.NDArray[np.float64], dt: float
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]] | None: ...


@dataclass
class DiffIKStatus:
    """What one :meth:`DifferentialIK.solve` did (``ik.status`` or ``solve(..., info=True)``).

    qp_status: "unconstrained" (no bound active: one linear solve), "optimal" (the QP solver with active
    bounds), "scaled" (``limits="scale"``: the whole step times ``scale``), "infeasible" (the QP solver
    found nothing; a zero step (or the bounds' nearest point to it) was returned).
    active_lower / active_upper: (dof,) bool, which coordinates' step sits on its lower / upper bound (the
    position, velocity or acceleration bound of that step). active_constraints: (m,) bool over the rows of
    the extra inequality blocks. residual: ‖e‖ of every PoseTarget's selected rows at q, before the step
    ([m] and [rad] mixed). stalled: the residual has not decreased by ``stall_decrease`` over the last
    ``stall_window`` steps, all of which had a bound active, and is above ``stall_residual``.
    """

    qp_status: str
    active_lower: npt.NDArray[np.bool_]
    active_upper: npt.NDArray[np.bool_]
    active_constraints: npt.NDArray[np.bool_]
    residual: float
    stalled: bool
    scale: float = 1.0
    step: int = 0
    active_joints: tuple[str, ...] = ()

    @property
    def bounds_active(self) -> bool:
        return bool(self.active_lower.any() or self.active_upper.any() or self.active_constraints.any())


class StallWarning(RuntimeWarning):
    """DifferentialIK's once-per-episode warning that the step stalled against its bounds."""


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
        if not isinstance(target.frame, str):
            raise OptionError(f"PoseTarget frame must be a frame name, got {target.frame!r:.60}")
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
        self.name = f"PoseTarget({target.frame!r})"
        _number(f"{self.name} gain", target.gain, 0.0, 1.0, open_low=True)
        _number(f"{self.name} weight", target.weight)
        self.A6 = np.zeros((6, robot.dof))
        self.e6 = np.zeros(6)
        self.ff6 = np.zeros(6)

    def checked(self) -> tuple[np.ndarray, np.ndarray | None, float, float]:
        """(T_target (4, 4), twist (6,) or None, gain, weight), each checked now (OptionError)."""
        target = self.target
        try:
            p, C = single_target(target.T_target, None, None)  # the check inverse_kinematics makes
        except KinematicsError as error:
            raise OptionError(f"{self.name}.T_target: {error}") from None
        assert p is not None and C is not None
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = C, p
        twist = None
        if target.twist is not None:
            try:
                twist = np.asarray(target.twist, dtype=float)
            except (TypeError, ValueError):
                twist = None
            if twist is None or twist.shape != (6,) or not np.isfinite(twist).all():
                raise OptionError(
                    f"{self.name}.twist must be None or finite [v; ω] of shape (6,) [m/s, rad/s], got "
                    f"{target.twist!r:.80}"
                )
        gain = _number(f"{self.name} gain", target.gain, 0.0, 1.0, open_low=True)
        return T, twist, gain, _number(f"{self.name} weight", target.weight)


class _Level:
    """One priority level: its pose terms and posture targets."""

    def __init__(self, robot: QPRobot, tasks: object, index: int) -> None:
        if isinstance(tasks, (PoseTarget, PostureTarget)) or not isinstance(tasks, Sequence):
            raise OptionError(
                f"DifferentialIK takes each priority level as a list of PoseTarget / PostureTarget entries, "
                f"got {tasks!r:.80} for level {index + 1}"
            )
        n = robot.dof
        self.poses: list[_PoseTerm] = []
        self.postures: list[PostureTarget] = []
        for task in tasks:
            if isinstance(task, PoseTarget):
                self.poses.append(_PoseTerm(robot, task))
            elif isinstance(task, PostureTarget):
                joints = task.joints
                if joints is not None and (isinstance(joints, str) or not isinstance(joints, Sequence)):
                    raise OptionError(f"PostureTarget joints must be a list of joint names, got {joints!r:.60}")
                unknown = set(joints or ()) - set(robot.joint_names)
                if unknown:
                    raise OptionError(
                        f"PostureTarget joints {sorted(unknown)} are not coordinates of the robot; "
                        f"known: {', '.join(robot.joint_names)}"
                    )
                task._mask = (
                    np.ones(n)
                    if joints is None
                    else np.array([1.0 if name in set(joints) else 0.0 for name in robot.joint_names])
                )
                _number("PostureTarget weight", task.weight)
                _number("PostureTarget gain", task.gain, 0.0, 1.0, open_low=True)
                self.postures.append(task)
            else:
                raise OptionError(f"tasks are PoseTarget or PostureTarget entries, got {task!r:.80}")
        self.H, self.c = np.zeros((n, n)), np.zeros(n)
        self.diag = self.H.reshape(-1)[:: n + 1]  # a view of H's diagonal


def _limits(
    robot: QPRobot, limits: npt.ArrayLike | Mapping[str, float] | None, urdf: npt.NDArray[np.float64], what: str
) -> npt.NDArray[np.float64]:
    """(dof,) limits [per second]: the URDF's ``urdf`` overridden by an array or a mapping name -> limit."""
    out = urdf.astype(float, copy=True)
    if limits is None:
        return out
    if isinstance(limits, Mapping):
        for name, value in limits.items():
            if name not in robot.joint_names:
                raise OptionError(f"{what} names unknown joint {name!r}; known: {', '.join(robot.joint_names)}")
            out[list(robot.joint_names).index(name)] = _limit_value(f"{what}[{name!r}]", value)
    else:
        try:
            out = np.array(limits, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise OptionError(f"{what} must be numbers of shape ({robot.dof},), got {limits!r:.60}") from None
        if out.shape != (robot.dof,):
            raise OptionError(f"{what} must have shape ({robot.dof},), got {out.shape}")
    if not (out >= 0).all():
        raise OptionError(f"{what} must be >= 0 (inf for none), got {out.tolist()}")
    return out


def _limit_value(what: str, value: object) -> float:
    if isinstance(value, (float, np.floating)) and value == math.inf:
        return math.inf
    return _number(what, value)


def urdf_velocity_limits(robot: QPRobot) -> npt.NDArray[np.float64]:
    """(dof,) the URDF's ``<limit velocity>`` of each coordinate's joint [rad/s | m/s]; inf where absent."""
    return _urdf_limits(robot, "velocity")


def urdf_effort_limits(robot: QPRobot) -> npt.NDArray[np.float64]:
    """(dof,) the URDF's ``<limit effort>`` of each coordinate's joint [N·m | N]; inf where absent."""
    return _urdf_limits(robot, "effort")


def _urdf_limits(robot: QPRobot, attribute: str) -> npt.NDArray[np.float64]:
    urdf = {j.name: getattr(j, attribute) for j in robot.description.joints}
    out = np.array([urdf.get(name) or np.inf for name in robot.joint_names], dtype=float).reshape(-1)
    out.flags.writeable = False
    return out


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
    each position limit then also lets the joint brake in time (q̇ <= sqrt(2 a (q_max − q))).
    position_limits: False ignores the joint limits. limits: "clip" (the QP: each bound cuts its own
    coordinate, which may turn the Cartesian direction) or "scale" (the unconstrained step times the largest
    s <= 1 that satisfies every bound: the direction is kept; "clip" when no such s exists). solver: "daqp"
    (default) or "proxqp". constraints: :class:`VelocityConstraint` blocks G q̇ ≤ h. stall_window (steps),
    stall_decrease (relative) and stall_residual: the stall test of :class:`DiffIKStatus`; warn_on_stall:
    warn (:class:`StallWarning`) the first time a step stalls after construction or :meth:`reset`.
    """

    def __init__(
        self,
        robot: QPRobot,
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
        self.damping = _number("damping", damping)
        self.lm_damping = _number("lm_damping", lm_damping)
        if isinstance(stall_window, bool) or not isinstance(stall_window, (int, np.integer)) or stall_window < 1:
            raise OptionError(f"stall_window must be a whole number of steps >= 1, got {stall_window!r}")
        self.stall_window = int(stall_window)
        self.stall_decrease = _number("stall_decrease", stall_decrease, 0.0, 1.0)
        self.stall_residual = _number("stall_residual", stall_residual)
        self.warn_on_stall, self.limits = bool(warn_on_stall), limits
        self.robot, self.solver = robot, solver
        kin = robot.engine
        self._model, self._coords = kin.model, kin.coordinates
        self._data = create_data(self._model, "a DifferentialIK")
        n = self.dof = robot.dof
        self._levels = [_Level(robot, level, i) for i, level in enumerate((tasks, *lower_levels))]
        if not any(level.poses or level.postures for level in self._levels):
            raise OptionError("DifferentialIK needs at least one task")
        self._pose_terms = [t for level in self._levels for t in level.poses]
        self._postures = [p for level in self._levels for p in level.postures]
        self.velocity_limits = _limits(robot, velocity_limits, urdf_velocity_limits(robot), "velocity_limits")
        self.acceleration_limits = _limits(
            robot, acceleration_limits, np.full(n, np.inf), "acceleration_limits"
        )
        if acceleration_limits is not None and not (self.acceleration_limits > 0).all():
            raise OptionError("acceleration_limits must be > 0 (inf for none)")
        self._has_acceleration = bool(np.isfinite(self.acceleration_limits).any())
        self._lower = robot.lower_limits if position_limits else np.full(n, -np.inf)
        self._upper = robot.upper_limits if position_limits else np.full(n, np.inf)
        self._lb, self._ub = np.zeros(n), np.zeros(n)
        self._no_active = np.zeros(n, dtype=bool)
        self._no_active.flags.writeable = False
        self._no_rows = np.zeros(0, dtype=bool)
        self._no_rows.flags.writeable = False
        self._constraints: list[VelocityConstraint] = []
        for constraint in constraints:
            self.add_constraint(constraint)
        self.last_error = np.full(6 * len(self._pose_terms), np.nan)
        self.qp_calls = 0
        """How many solves needed the QP solver (a bound active); the others were one linear solve."""
        self.reset()

    # -- state ------------------------------------------------------------------------------------
    def reset(self, qdot: npt.ArrayLike | None = None) -> None:
        """Start a new episode: the previous q̇ of the acceleration limits becomes ``qdot`` (default zero:
        at rest), the stall history is cleared and the stall warning may be given again."""
        self._qdot = (
            np.zeros(self.dof) if qdot is None else self._coords.check(qdot, name="qdot", allow_batch=False).copy()
        )
        self._history: deque[float] = deque(maxlen=self.stall_window + 1)
        self._active_run = 0
        self._warned = False
        self._steps = 0
        empty = np.zeros(self.dof, dtype=bool)
        self.status = DiffIKStatus("unconstrained", empty, empty, np.zeros(0, dtype=bool), math.nan, False)
        """The :class:`DiffIKStatus` of the last :meth:`solve`."""

    def add_constraint(self, constraint: VelocityConstraint) -> None:
        """Plug in an extra block G q̇ ≤ h (:class:`VelocityConstraint`), evaluated at every solve."""
        if not callable(getattr(constraint, "inequalities", None)):
            raise OptionError(
                f"a constraint needs a method inequalities(q, dt) -> (G, h) or None, got {constraint!r:.60}"
            )
        self._constraints.append(constraint)

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
        self, q: npt.ArrayLike, dt: float, *, info: Literal[False] = ..., previous_qdot: npt.ArrayLike | None = ...
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
        dt = _number("dt [s]", dt, 0.0, 1e6, open_low=True)
        q = self._coords.check(q, allow_batch=False)
        if previous_qdot is not None:
            self._qdot = self._coords.check(previous_qdot, name="previous_qdot", allow_batch=False).copy()
        model, data, n = self._model, self._data, self.dof
        qp = q if self._coords.identity else self._coords.to_pinocchio(q)
        if self._pose_terms:
            if n:
                pin.computeJointJacobians(model, data, qp)
            else:  # Pinocchio's frame Jacobian crashes at nv = 0: the poses only
                pin.forwardKinematics(model, data, qp)
        # each level: (H, c, wsq, A rows) with the cost ½ΔqᵀHΔq + cᵀΔq (damping not included)
        self._residual_sq, stack, offset, terms = 0.0, len(self._levels) > 1, 0, []
        for level in self._levels:
            terms.append(self._level_terms(level, q, dt, offset, stack))
            offset += len(level.poses)
        residual = math.sqrt(self._residual_sq)
        lb, ub = self._bounds(q, dt)
        G, h = self._inequalities(q, dt)
        if n == 0:
            step, status = np.zeros(0), "unconstrained"
            scale = 1.0
        else:
            step, status, scale = self._hierarchy(terms, lb, ub, G, h)
        qdot = np.asarray(step / dt, dtype=np.float64)
        self._qdot = qdot.copy()
        self._record(status, scale, step, lb, ub, G, h, residual)
        return (qdot, self.status) if info else qdot

    def _level_terms(
        self, level: _Level, q: np.ndarray, dt: float, offset: int, stack: bool
    ) -> tuple[np.ndarray, np.ndarray, float, np.ndarray | None]:
        """(H, c, Σ w‖k e‖², A rows or None): the level's cost ½ΔqᵀHΔq + cᵀΔq without the damping."""
        n = self.dof
        H, c, diag = level.H, level.c, level.diag
        H.fill(0.0)
        c.fill(0.0)
        weighted_sq = 0.0
        rows: list[np.ndarray] = []
        for k, term in enumerate(level.poses):
            T, twist, gain, w = term.checked()
            A, e, ff = self._pose_rows(term, T, twist)
            self.last_error[6 * (offset + k) : 6 * (offset + k) + 6] = e
            if not term.all_rows:
                A, e, ff = A[term.rows], e[term.rows], ff[term.rows]
            self._residual_sq += float(e @ e)
            e *= gain
            b = e + ff * dt if twist is not None else e
            if stack:
                rows.append(A.copy())
            if n:
                if w != 1.0:
                    H += w * (A.T @ A)
                    c -= w * (A.T @ b)
                else:
                    H += A.T @ A
                    c -= A.T @ b
            weighted_sq += w * float(e @ e)
        for posture in level.postures:
            mask = posture._mask
            assert mask is not None  # set by _Level
            q_ref = self._coords.check(posture.q_ref, name="PostureTarget q_ref", allow_batch=False)
            w = _number("PostureTarget weight", posture.weight)
            gain = _number("PostureTarget gain", posture.gain, 0.0, 1.0, open_low=True)
            e = gain * (q_ref - q) * mask
            diag += w * mask
            c -= w * e
            weighted_sq += w * float(e @ e)
            if stack:
                rows.append(np.eye(n)[mask > 0])
        diag += self.damping + self.lm_damping * weighted_sq
        return H, c, weighted_sq, (np.vstack(rows) if rows else np.zeros((0, n))) if stack else None

    def _bounds(self, q: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Step bounds lb <= Δq <= ub [rad | m] from the position, velocity and acceleration limits."""
        vmax, lo, hi = self.velocity_limits, self._lb, self._ub
        np.subtract(self._upper, q, out=hi)
        hi /= dt
        np.minimum(hi, vmax, out=hi)
        np.subtract(self._lower, q, out=lo)
        lo /= dt
        np.maximum(lo, -vmax, out=lo)
        if self._has_acceleration:  # brake in time: |q̇| <= sqrt(2 a d) to each position limit
            a = self.acceleration_limits
            with np.errstate(invalid="ignore"):  # inf·0: NaN, ignored by fmin/fmax
                np.fmin(hi, np.sqrt(2 * a * np.maximum(self._upper - q, 0.0)), out=hi)
                np.fmax(lo, -np.sqrt(2 * a * np.maximum(q - self._lower, 0.0)), out=lo)
        np.maximum(hi, np.minimum(lo, 0.0), out=hi)  # q outside its limits: move back as fast as allowed
        np.minimum(lo, hi, out=lo)
        if self._has_acceleration:  # hard: the box is clipped into q̇_prev ± a dt
            a_lo, a_hi = self._qdot - self.acceleration_limits * dt, self._qdot + self.acceleration_limits * dt
            np.clip(lo, a_lo, a_hi, out=lo)
            np.clip(hi, a_lo, a_hi, out=hi)
        lo *= dt
        hi *= dt
        return lo, hi

    def _inequalities(self, q: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """The extra blocks stacked, in step units: G Δq <= h·dt."""
        blocks_G, blocks_h = [], []
        for constraint in self._constraints:
            got = constraint.inequalities(q, dt)
            if got is None:
                continue
            G, h = np.asarray(got[0], dtype=float), np.asarray(got[1], dtype=float).reshape(-1)
            G = G.reshape(-1, self.dof) if G.size or not self.dof else G
            if G.ndim != 2 or G.shape[1] != self.dof or h.shape != (G.shape[0],) or not (
                np.isfinite(G).all() and not np.isnan(h).any()
            ):
                raise OptionError(
                    f"constraint {constraint!r:.60} returned G {G.shape}, h {h.shape}: need (m, {self.dof}) "
                    "and (m,), finite (h may be +inf)"
                )
            blocks_G.append(G)
            blocks_h.append(h * dt)
        if not blocks_G:
            return np.zeros((0, self.dof)), np.zeros(0)
        return np.vstack(blocks_G), np.concatenate(blocks_h)

    def _hierarchy(
        self,
        terms: list[tuple[np.ndarray, np.ndarray, float, np.ndarray]],
        lb: np.ndarray,
        ub: np.ndarray,
        G: np.ndarray,
        h: np.ndarray,
    ) -> tuple[np.ndarray, str, float]:
        """Solve the levels in turn; "scale" first solves them without bounds, then scales."""
        if self.limits == "scale":
            free = np.full(self.dof, np.inf)
            step, status = self._levels_solve(terms, -free, free, np.zeros((0, self.dof)), np.zeros(0))
            scale = _largest_scale(step, lb, ub, G, h)
            if scale is not None:
                return step * scale, ("unconstrained" if scale == 1.0 else "scaled"), scale
        step, status = self._levels_solve(terms, lb, ub, G, h)
        return step, status, 1.0

    def _levels_solve(
        self,
        terms: list[tuple[np.ndarray, np.ndarray, float, np.ndarray]],
        lb: np.ndarray,
        ub: np.ndarray,
        G: np.ndarray,
        h: np.ndarray,
    ) -> tuple[np.ndarray, str]:
        n = self.dof
        step = np.zeros(n)
        Z: np.ndarray | None = None  # basis of the free directions (None: all of R^n)
        above: list[np.ndarray] = []
        worst = "unconstrained"
        for H, c, _, A in terms:  # A: None with one level
            if Z is None:
                z, status = self._qp(H, c, lb, ub, G, h, None, step)
                step = z
            else:  # H holds the damping: Zᵀ H Z has it on z (Z orthonormal); ‖Δq‖² regularized as a whole
                Hz = Z.T @ H @ Z
                cz = Z.T @ (H @ step + c)
                z, status = self._qp(Hz, cz, lb, ub, G, h, Z, step)
                step = step + Z @ z
            if status != "unconstrained":
                worst = status if worst != "infeasible" else worst
            if A is not None and len(terms) > 1:
                above.append(A)
                stacked = np.vstack(above)
                if stacked.shape[0]:
                    _, s, Vt = np.linalg.svd(stacked)
                    rank = int((s > _NULL_TOL * max(1.0, float(s[0]) if len(s) else 0.0)).sum())
                    Z = Vt[rank:].T
                    if Z.shape[1] == 0:
                        break
        return step, worst

    def _qp(
        self,
        H: np.ndarray,
        c: np.ndarray,
        lb: np.ndarray,
        ub: np.ndarray,
        G: np.ndarray,
        h: np.ndarray,
        Z: np.ndarray | None,
        base: np.ndarray,
    ) -> tuple[np.ndarray, str]:
        """argmin ½zᵀHz + cᵀz with lb <= base + Z z <= ub and G (base + Z z) <= h (Z None: z = Δq, base 0)."""
        # H is positive definite: when the unconstrained minimizer −H⁻¹c satisfies the bounds it is the
        # QP's solution (no bound active), found by one linear solve; otherwise the QP solver decides.
        try:
            z = np.linalg.solve(H, -c)
        except np.linalg.LinAlgError:
            z = None
        if z is not None and np.isfinite(z).all():
            x = z if Z is None else base + Z @ z
            if (x >= lb).all() and (x <= ub).all() and (not len(h) or (G @ x <= h).all()):
                return z, "unconstrained"
        self.qp_calls += 1
        import qpsolvers  # only when a bound is active: keeps `import kinengine` light

        lbc, ubc = np.clip(lb - base, -_BIG, _BIG), np.clip(ub - base, -_BIG, _BIG)
        Gz, hz = (G, h) if Z is None else (G @ Z, h - G @ base)
        hz = np.clip(hz, -_BIG, _BIG)
        if Z is None:
            z = qpsolvers.solve_qp(
                H, c, G=Gz if len(hz) else None, h=hz if len(hz) else None, lb=lbc, ub=ubc, solver=self.solver
            )
        else:
            finite = np.isfinite(lb - base) | np.isfinite(ub - base)
            Gb = np.vstack([Z[finite], -Z[finite], Gz])
            hb = np.concatenate([ubc[finite], -lbc[finite], hz])
            z = qpsolvers.solve_qp(H, c, G=Gb if len(hb) else None, h=hb if len(hb) else None, solver=self.solver)
        if z is None or not np.isfinite(z).all():  # no feasible step: the bounds' point nearest zero
            z = np.zeros(H.shape[0])
            if Z is None:
                np.clip(z, lb, ub, out=z)
            return z, "infeasible"
        if Z is None:
            np.clip(z, lb, ub, out=z)  # the solver's tolerance (~1e-14) off a bound: onto it
        return z, "optimal"

    def _record(
        self,
        status: str,
        scale: float,
        step: np.ndarray,
        lb: np.ndarray,
        ub: np.ndarray,
        G: np.ndarray,
        h: np.ndarray,
        residual: float,
    ) -> None:
        if status == "unconstrained":
            active_lower = active_upper = self._no_active
            active_rows = self._no_rows if not len(h) else np.zeros(len(h), dtype=bool)
        else:
            active_lower = step <= lb + _ACTIVE_TOL
            active_upper = step >= ub - _ACTIVE_TOL
            active_rows = G @ step >= h - _ACTIVE_TOL if len(h) else self._no_rows
        active = bool(active_lower.any() or active_upper.any() or active_rows.any())
        self._active_run = self._active_run + 1 if active else 0
        history = self._history
        history.append(residual)
        stalled = (
            self._active_run >= self.stall_window
            and len(history) == self.stall_window + 1
            and residual > self.stall_residual
            and residual >= (1.0 - self.stall_decrease) * history[0]
        )
        self._steps += 1
        names = (
            tuple(name for name, on in zip(self.robot.joint_names, active_lower | active_upper, strict=True) if on)
            if active
            else ()
        )
        self.status = DiffIKStatus(
            status, active_lower, active_upper, active_rows, residual, stalled, scale, self._steps, names
        )
        if stalled and self.warn_on_stall and not self._warned:
            self._warned = True
            warnings.warn(
                f"DifferentialIK stalled at step {self._steps}: the task residual {residual:.3g} has not "
                f"decreased over {self.stall_window} steps while bounds were active "
                f"({', '.join(names) or 'extra constraints'}); check the target's reachability and the limits",
                StallWarning,
                stacklevel=3,
            )

    def _pose_rows(
        self, term: _PoseTerm, T_target: np.ndarray, twist: np.ndarray | None
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(A (6, dof), e (6,), V (6,)): rows [position; rotation] of the module doc at the current Data."""
        model, data, n = self._model, self._data, self.dof
        fold = self._coords.fold
        MA = pin.updateFramePlacement(model, data, term.fid)
        JA = fold(pin.getFrameJacobian(model, data, term.fid, _LWA).reshape(6, -1)) if n else np.zeros((6, 0))
        if term.fb is None:
            C, p, Jv, Jw = MA.rotation, MA.translation, JA[:3], JA[3:]
        else:
            MB = pin.updateFramePlacement(model, data, term.fb)
            JB = fold(pin.getFrameJacobian(model, data, term.fb, _LWA).reshape(6, -1)) if n else np.zeros((6, 0))
            inner = relative_terms(MA.homogeneous, JA, MB.homogeneous, JB)
            CB = MB.rotation
            C, p = CB.T @ MA.rotation, CB.T @ (MA.translation - MB.translation)
            Jv, Jw = CB.T @ inner[:3], CB.T @ inner[3:]
        C_target = T_target[:3, :3]
        e, A, ff = term.e6, term.A6, term.ff6
        R = C.T @ C_target
        Jr = pin.Jlog3(R)  # d log3(R exp(δ)) = Jr δ
        e[:3] = T_target[:3, 3] - p
        e[3:] = pin.log3(R)
        A[:3] = Jv
        A[3:] = Jr @ (C_target.T @ Jw)
        if twist is not None:
            ff[:3] = twist[:3]
            ff[3:] = Jr @ (C_target.T @ twist[3:])
        return A, e.copy(), ff


def _largest_scale(step: np.ndarray, lb: np.ndarray, ub: np.ndarray, G: np.ndarray, h: np.ndarray) -> float | None:
    """The largest s in [0, 1] with lb <= s·step <= ub and s·G step <= h, or None if there is none."""
    lo, hi = 0.0, 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        for d, low, high in ((step, lb, ub), (G @ step if len(h) else np.zeros(0), np.full(len(h), -np.inf), h)):
            pos, neg, zero = d > 0, d < 0, d == 0
            if ((low[zero] > 0) | (high[zero] < 0)).any():
                return None
            if pos.any():
                hi = min(hi, float(np.min(high[pos] / d[pos])))
                lo = max(lo, float(np.max(low[pos] / d[pos])))
            if neg.any():
                hi = min(hi, float(np.min(low[neg] / d[neg])))
                lo = max(lo, float(np.max(high[neg] / d[neg])))
    return hi if hi >= lo and hi >= 0.0 else None


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
    "urdf_effort_limits",
    "urdf_velocity_limits",
]
