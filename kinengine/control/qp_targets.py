"""What DifferentialIK takes and gives (see :mod:`kinengine.control.qp` for the math): the targets
(:class:`PoseTarget`, :class:`PostureTarget`), the pluggable inequality block (:class:`VelocityConstraint`),
and the targets resolved and checked against a robot (rows A, error e and
feed-forward V of a pose target, in [m] and [rad])."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..errors import KinematicsError, OptionError
from ..kinematics.options import number_option
from ..kinematics.relative import relative_terms
from .ik_target import ROW_NAMES as ROWS
from .ik_target import single_target
from .robot_like import RobotLike

_LWA = pin.LOCAL_WORLD_ALIGNED


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
            self.weight = number_option("PoseTarget cost", self.cost) ** 2


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
    _partial: bool = field(default=False, init=False, repr=False)  # set by Level: some joints only

    def __post_init__(self) -> None:
        if self.cost is not None:
            self.weight = number_option("PostureTarget cost", self.cost) ** 2


class VelocityConstraint(Protocol):
    """An extra block of linear inequalities on q̇ that another module plugs into :class:`DifferentialIK`
    (``constraints=[...]`` or :meth:`DifferentialIK.add_constraint`): a collision constraint, a workspace
    wall, a velocity damper.

    ``inequalities(robot, q, dt)`` is called once per :meth:`DifferentialIK.solve` with the solver's robot
    and the checked q (dof,), and returns (G (m, dof), h (m,)) meaning G q̇ ≤ h, q̇ in [rad/s | m/s] and h
    in G's row units per second (e.g. [m/s] for a distance rate), or None when nothing constrains this
    step. Every priority level and ``limits="scale"`` respect it; ``status.active_constraints`` says which
    rows bind.
    """

    def inequalities(
        self, robot: RobotLike, q: npt.NDArray[np.float64], dt: float
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]] | None: ...


def stacked_inequalities(
    constraints: Sequence[VelocityConstraint],
    robot: RobotLike,
    q: np.ndarray,
    dt: float,
    no_G: np.ndarray,
    no_h: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The blocks of ``constraints`` of ``robot`` at q stacked, in step units: G Δq <= h·dt (``no_G``,
    ``no_h``: the empty (0, dof) and (0,) answer); OptionError for a block of the wrong shape or not
    finite."""
    if not constraints:
        return no_G, no_h
    dof = no_G.shape[1]
    blocks_G, blocks_h = [], []
    for constraint in constraints:
        got = constraint.inequalities(robot, q, dt)
        if got is None:
            continue
        G, h = np.asarray(got[0], dtype=float), np.asarray(got[1], dtype=float).reshape(-1)
        G = G.reshape(-1, dof) if G.size or not dof else G
        if (
            G.ndim != 2
            or G.shape[1] != dof
            or h.shape != (G.shape[0],)
            or not (np.isfinite(G).all() and not np.isnan(h).any())
        ):
            raise OptionError(
                f"constraint {constraint!r:.60} returned G {G.shape}, h {h.shape}: need (m, {dof}) "
                "and (m,), finite (h may be +inf)"
            )
        blocks_G.append(G)
        blocks_h.append(h * dt)
    if not blocks_G:
        return no_G, no_h
    return np.vstack(blocks_G), np.concatenate(blocks_h)


class PoseTerm:
    """A PoseTarget resolved against the robot: frame ids, row indices, buffers."""

    def __init__(self, robot: RobotLike, target: PoseTarget) -> None:
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
        number_option(f"{self.name} gain", target.gain, 0.0, 1.0, open_low=True)
        number_option(f"{self.name} weight", target.weight)
        self.A6 = np.zeros((6, robot.dof))
        self.e6 = np.zeros(6)
        self.ff6 = np.zeros(6)
        self._checked_key: bytes | None = None
        self._checked: tuple[np.ndarray, np.ndarray] = (np.zeros(3), np.eye(3))

    def checked(self) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, float, float]:
        """(p_target (3,), C_target (3, 3), twist (6,) or None, gain, weight), each checked now
        (OptionError)."""
        target = self.target
        T = target.T_target
        key = T.tobytes() if type(T) is np.ndarray and T.dtype == np.float64 and T.shape == (4, 4) else None
        if key is not None and key == self._checked_key:  # the very values checked at the last step
            p, C = self._checked
        else:
            try:
                p_or_none, C_or_none = single_target(T, None, None)  # the check inverse_kinematics makes
            except KinematicsError as error:
                raise OptionError(f"{self.name}.T_target: {error}") from None
            assert p_or_none is not None and C_or_none is not None
            p, C = p_or_none, C_or_none
            self._checked_key, self._checked = key, (p, C)
        twist = None
        if target.twist is not None:
            try:
                twist = np.asarray(target.twist, dtype=float)
            except (TypeError, ValueError):
                twist = None
            if (
                twist is None
                or twist.shape != (6,)
                or not (math.isfinite(twist @ twist) or np.isfinite(twist).all())  # the cheap test first
            ):
                raise OptionError(
                    f"{self.name}.twist must be None or finite [v; ω] of shape (6,) [m/s, rad/s], got "
                    f"{target.twist!r:.80}"
                )
        gain = number_option(f"{self.name} gain", target.gain, 0.0, 1.0, open_low=True)
        return p, C, twist, gain, number_option(f"{self.name} weight", target.weight)

    def rows_at(
        self,
        model: pin.Model,
        data: pin.Data,
        fold: Callable[[np.ndarray], np.ndarray],
        p_target: np.ndarray,
        C_target: np.ndarray,
        twist: np.ndarray | None,
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(A (6, dof), e (6,), V (6,)): rows [position; rotation] of :mod:`.qp`'s doc and feed-forward V,
        at ``data`` (joint Jacobians computed); the term's buffers, overwritten at the next call."""
        n, term = self.A6.shape[1], self
        MA = pin.updateFramePlacement(model, data, term.fid)
        JA = fold(pin.getFrameJacobian(model, data, term.fid, _LWA).reshape(6, -1)) if n else np.zeros((6, 0))
        if term.fb is None:
            C, p, Jv, Jw = MA.rotation, MA.translation, JA[:3], JA[3:]
        else:
            MB = pin.updateFramePlacement(model, data, term.fb)
            JB = (
                fold(pin.getFrameJacobian(model, data, term.fb, _LWA).reshape(6, -1))
                if n
                else np.zeros((6, 0))
            )
            inner = relative_terms(MA.homogeneous, JA, MB.homogeneous, JB)
            CB = MB.rotation
            C, p = CB.T @ MA.rotation, CB.T @ (MA.translation - MB.translation)
            Jv, Jw = CB.T @ inner[:3], CB.T @ inner[3:]
        e, A, ff = term.e6, term.A6, term.ff6
        R = C.T @ C_target
        Jr = pin.Jlog3(R)  # d log3(R exp(δ)) = Jr δ
        e[:3] = p_target - p
        e[3:] = pin.log3(R)
        A[:3] = Jv
        A[3:] = Jr @ (C_target.T @ Jw)
        if twist is not None:
            ff[:3] = twist[:3]
            ff[3:] = Jr @ (C_target.T @ twist[3:])
        return A, e, ff


class Level:
    """One priority level: its pose terms and posture targets."""

    def __init__(self, robot: RobotLike, tasks: object, index: int) -> None:
        if isinstance(tasks, (PoseTarget, PostureTarget)) or not isinstance(tasks, Sequence):
            raise OptionError(
                f"DifferentialIK takes each priority level as a list of PoseTarget / PostureTarget entries, "
                f"got {tasks!r:.80} for level {index + 1}"
            )
        n = robot.dof
        self.poses: list[PoseTerm] = []
        self.postures: list[PostureTarget] = []
        for task in tasks:
            if isinstance(task, PoseTarget):
                self.poses.append(PoseTerm(robot, task))
            elif isinstance(task, PostureTarget):
                joints = task.joints
                if joints is not None and (isinstance(joints, str) or not isinstance(joints, Sequence)):
                    raise OptionError(
                        f"PostureTarget joints must be a list of joint names, got {joints!r:.60}"
                    )
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
                task._partial = joints is not None and not task._mask.all()
                number_option("PostureTarget weight", task.weight)
                number_option("PostureTarget gain", task.gain, 0.0, 1.0, open_low=True)
                self.postures.append(task)
            else:
                raise OptionError(f"tasks are PoseTarget or PostureTarget entries, got {task!r:.80}")
        self.H, self.c, self.AtA, self.Atb = np.zeros((n, n)), np.zeros(n), np.zeros((n, n)), np.zeros(n)
        self.diag = self.H.reshape(-1)[:: n + 1]  # a view of H's diagonal


__all__ = [
    "ROWS",
    "Level",
    "PoseTarget",
    "PoseTerm",
    "PostureTarget",
    "VelocityConstraint",
    "number_option",
    "stacked_inequalities",
]
