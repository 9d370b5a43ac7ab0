"""Inverse kinematics for several frames at once: ``target`` a mapping {frame name: T_IF (4, 4)}.

Frames and units: every target T_IF is the frame F's pose in the root frame I (p_d [m], C_d); each frame's
error is the single-frame one (:mod:`kinengine.control.ik`): e_F = (p_d − p, log3(C_d Cᵀ)) [m, rad] in I,
or, with ``rows=``/``weights=``, e_D = (C_dᵀ e_p, C_dᵀ e_R) in the frame's target frame D, kept rows only,
each times √w. Its Jacobian is J_F = J_e0 ("local_world_aligned", folded with the coordinate map M for
mimic robots), rotated and cut the same way. The solver stacks them, e = (e_F1, e_F2, ...),
J = (J_F1; J_F2; ...), and takes the single-frame step (:func:`.ik_step.take_step`): Δq = W⁻¹Jᵀ (J W⁻¹Jᵀ +
λ² S⁻²)⁻¹ e (+ the nullspace pull), S weighting a full pose's rotation rows by 0.2 m/rad, λ² =
DAMPING_SCALE·(weighted |e|²) + λ_min², Chan & Dubey's limit weights W, every iterate clipped into the limits.
Success: EVERY frame within ``tol_position`` [m] and ``tol_rotation`` [rad]. Attempts are ranked by
Σ_F (|e_p| + 0.2 m/rad·|e_R|) and give way to the next by the single-frame rules (still above ``GIVE_UP``
after ``PROBE_ITERATIONS`` iterations, or stalled).
Seeds: ``q0`` if given (never gives up early), else the ``NEAREST_SEEDS`` stored configurations
(:mod:`.ik_seeds`) nearest each frame's target, all of them ranked by that sum over every frame, and the
middle of the ranges (or ``nullspace_target``); then ``restarts`` random ones.
The result's position_error / rotation_error are the maxima over the frames; ``frame_errors`` holds each
frame's (position error [m], rotation error [rad]).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from ..errors import OptionError, ParameterizationError
from . import ik_step as step
from .ik_seeds import SEED_ROTATION_WEIGHT, first_seeds
from .ik_solver import IKResult
from .ik_target import Options, Problem, RandomSource, checked_problem, single_target

if TYPE_CHECKING:  # named for the checker only
    from .robot_like import RobotLike


@dataclass(frozen=True)
class MultiIKResult(IKResult):
    """An :class:`IKResult` for several frames: position_error / rotation_error are the maxima over the
    frames, ``frame_errors`` {frame: (position error [m], rotation error [rad])} each frame's own."""

    frame_errors: dict[str, tuple[float, float]] | None = None


@dataclass(frozen=True)
class FrameGoal:
    """One frame's validated options (its :class:`Problem`: fid, rows, weights), target p_d [m], C_d in I."""

    problem: Problem
    p_d: np.ndarray
    C_d: np.ndarray


def _per_frame(name: str, value: object, frames: Mapping[str, object]) -> dict[str, object]:
    """``rows``/``weights`` for each frame: one spec for all, or a mapping {frame: spec} (missing: None)."""
    if not isinstance(value, Mapping):
        return dict.fromkeys(frames, value)
    if not value:
        raise OptionError(
            f"`{name}` is an empty mapping; give {{frame: spec}} for some of the target's frames, "
            f"or None for all six rows of every frame"
        )
    unknown = [key for key in value if key not in frames]
    if unknown:
        raise OptionError(
            f"`{name}` names {unknown[0]!r}, which is not a frame of the target {list(frames)}; "
            f"name only frames of the target (the others keep all six rows, weight 1)"
        )
    return {frame: value.get(frame) for frame in frames}


def checked_goals(
    robot: RobotLike, target: Mapping[Any, Any], rows: object, weights: object, options: Options
) -> list[FrameGoal]:
    """Each frame's target and options checked (OptionError, FrameNotFoundError, ParameterizationError)."""
    if not target:
        raise OptionError(
            "`target` is an empty mapping; give {frame name: pose (4, 4)} for at least one frame"
        )
    for name in target:
        if not isinstance(name, str):
            raise OptionError(f"`target`'s keys must be frame names (str), got {name!r}")
    frames: dict[str, Any] = {str(name): pose for name, pose in target.items()}
    frame_rows, frame_weights = _per_frame("rows", rows, frames), _per_frame("weights", weights, frames)
    goals = []
    for frame, pose in frames.items():
        problem = checked_problem(robot, frame, frame_rows[frame], frame_weights[frame], *options.values())
        try:
            pose_shaped = not isinstance(pose, (str, bytes)) and np.shape(pose) == (4, 4)
        except ValueError:  # ragged nesting
            pose_shaped = False
        if not pose_shaped:
            raise ParameterizationError(
                f"`target[{frame!r}]` must be a pose (4, 4), got {pose!r:.60}; several frames take one "
                "pose T_IF each (for parameters χ or a batch, solve one frame at a time)"
            )
        try:
            p_d, C_d = single_target(pose, None, None)
        except ParameterizationError as error:
            raise ParameterizationError(f"`target[{frame!r}]`: {error}") from None
        assert p_d is not None and C_d is not None  # a (4, 4) pose fixes both
        goals.append(FrameGoal(problem, p_d, C_d))
    return goals


def _seeds(robot: RobotLike, goals: list[FrameGoal], q0: np.ndarray | None) -> np.ndarray:
    """The seeded attempts' starts (S, dof): q0, or the stored seeds nearest any frame's target ranked by
    Σ_F (|Δp| + 0.2·‖ΔC‖_F/√2) over the frames' kept rows (‖ΔC‖_F/√2 = 2 sin(θ/2) ≈ θ, the metric of
    the stored tables), then the middle of the ranges (or the nullspace target)."""
    if q0 is not None:
        return first_seeds(robot, goals[0].problem, goals[0].p_d[None], goals[0].C_d[None], q0)[0]
    per_frame = [first_seeds(robot, g.problem, g.p_d[None], g.C_d[None], None)[0] for g in goals]
    if len(goals) == 1:
        return per_frame[0]
    candidates = np.concatenate([seeds[:-1] for seeds in per_frame])
    score, n = np.zeros(len(candidates)), len(candidates)
    for g in goals:
        T, rows = robot.frame_pose(candidates, g.problem.frame), g.problem.rows
        d = g.p_d - T[:, :3, 3]
        if rows is not None:
            d = (d @ g.C_d)[:, rows[rows < 3]]  # C_dᵀ Δp, kept rows
        score += np.sqrt(np.einsum("ij,ij->i", d, d))
        if rows is None or rows[-1] >= 3:  # rows are sorted: a rotation row is kept
            dC = (T[:, :3, :3] - g.C_d).reshape(n, 9)
            score += SEED_ROTATION_WEIGHT / math.sqrt(2.0) * np.sqrt(np.einsum("ij,ij->i", dC, dC))
    return np.concatenate((candidates[np.argsort(score, kind="stable")], per_frame[0][-1:]))


def _layout(goals: list[FrameGoal]) -> list[tuple]:
    """Per frame: (fid, p_d, C_d, rows slice start, stop, S or None, √w or None, kept position rows), S the
    kept rows of blockdiag(C_dᵀ, C_dᵀ) (k, 6): e_D = S e, J_D = S J."""
    layout, start = [], 0
    for g in goals:
        rows = g.problem.rows
        if rows is None:
            S, stop = None, start + 6
        else:
            S, stop = np.zeros((6, 6)), start + len(rows)
            S[:3, :3] = S[3:, 3:] = g.C_d.T
            S = np.ascontiguousarray(S[rows])
        prows = g.problem.position_rows
        layout.append((g.problem.fid, g.p_d, g.C_d, start, stop, S, g.problem.sqrt_weights, prows))
        start = stop
    return layout


def solve_frames(
    robot: RobotLike, goals: list[FrameGoal], q0: np.ndarray | None, generator: RandomSource
) -> MultiIKResult:
    """Attempts from each seed, then ``restarts`` random ones; the first that brings every frame within
    the tolerances (or the best by Σ_F score) wins. The linear algebra is the single-frame solver's
    (Cholesky, LAPACK ``dposv``, least squares if that fails), so one frame gives its iterates."""
    from scipy.linalg.lapack import dposv

    kin = robot.engine
    joints = kin.coordinates
    model, data = kin.model, kin.data()
    lower, upper = joints.lower, joints.upper
    shared = goals[0].problem
    tol_p, tol_r, max_iterations = shared.tol_position, shared.tol_rotation, shared.max_iterations
    damping_sq, q_ns, gain = shared.damping_sq, shared.q_ns, shared.gain
    seeds = _seeds(robot, goals, q0)
    attempts = len(seeds) + shared.restarts
    pinocchio_q, fold, identity = kin.pinocchio_q, joints.fold, joints.identity
    jacobians, get_jacobian, place, log3, LWA = (
        pin.computeJointJacobians,
        pin.getFrameJacobian,
        pin.updateFramePlacement,
        pin.log3,
        pin.LOCAL_WORLD_ALIGNED,
    )
    subtract, hypot, sqrt = np.subtract, math.hypot, math.sqrt
    layout = _layout(goals)
    m = layout[-1][4]
    err, J, e, A = np.empty(m), np.empty((m, robot.dof)), np.empty(6), np.empty((m, m))
    e_p, e_r = e[:3], e[3:]  # views
    limits = step.limit_weights(kin)
    weigh, bounds = limits.inverse_weights_one if limits.any else None, (lower, upper)
    rotation_sq = step.ROTATION_ROW_WEIGHT**2  # a full pose's rotation rows weigh ρ, as in the single solver:
    row_damping = np.ones(m)  # (J W⁻¹Jᵀ + λ² S⁻²) with S = diag(1, 1, 1, ρ, ρ, ρ) on those blocks
    for _, _, _, start, stop, S, _, _ in layout:
        if S is None:
            row_damping[start:stop] = step.POSE_ROW_DAMPING
    best, total = None, 0
    for attempt in range(attempts):
        q = (seeds[attempt] if attempt < len(seeds) else generator.configurations(robot)).copy()
        last = attempt == attempts - 1 or (attempt == 0 and shared.patient_first)
        iteration, previous = 0, None
        history: list[float] = []  # the score at each iteration
        while True:
            jacobians(model, data, q if identity else pinocchio_q(q))
            per_frame = []
            score, squared, done = 0.0, 0.0, True
            for fid, p_d, C_d, start, stop, S, sqrt_w, position_rows in layout:
                M = place(model, data, fid)
                subtract(p_d, M.translation, out=e_p)
                e_r[:] = log3(C_d @ M.rotation.T)
                if S is None:
                    err[start:stop] = e
                    e0, e1, e2, e3, e4, e5 = e.tolist()
                    ep, er = hypot(e0, e1, e2), hypot(e3, e4, e5)
                    squared += e0 * e0 + e1 * e1 + e2 * e2 + rotation_sq * (e3 * e3 + e4 * e4 + e5 * e5)
                else:
                    e_d = S @ e
                    ep = sqrt(float(e_d[position_rows] @ e_d[position_rows]))
                    er = sqrt(float(e_d[~position_rows] @ e_d[~position_rows]))
                    kept = err[start:stop]
                    kept[:] = e_d if sqrt_w is None else e_d * sqrt_w
                    squared += float(kept @ kept)
                per_frame.append((ep, er))
                score += ep + SEED_ROTATION_WEIGHT * er
                done = done and ep <= tol_p and er <= tol_r
            if (
                done
                or iteration == max_iterations
                or (not last and step.gives_way(iteration, score, history))
            ):
                break
            history.append(score)
            iteration += 1
            for fid, _, _, start, stop, S, sqrt_w, _ in layout:
                J_F = get_jacobian(model, data, fid, LWA).reshape(6, -1)
                if not identity:
                    J_F = fold(J_F)
                if S is None:
                    J[start:stop] = J_F
                elif sqrt_w is None:
                    J[start:stop] = S @ J_F
                else:
                    J[start:stop] = (S @ J_F) * sqrt_w[:, None]
            diagonal = step.damping(squared, damping_sq) * row_damping
            previous = step.take_step(
                q, J, err, A, diagonal, weigh, previous, bounds, (q_ns, gain, score), dposv
            )
        total += iteration
        if best is None or score < best[2]:
            best = (q, per_frame, score, attempt, done)
        if done:
            break
    assert best is not None  # attempts >= 1: the seeds hold at least one start
    q, per_frame, _, attempt, done = best
    limits.wrap(q)
    errors_by_frame = {g.problem.frame: pe for g, pe in zip(goals, per_frame, strict=True)}
    ep, er = max(pe[0] for pe in per_frame), max(pe[1] for pe in per_frame)
    return MultiIKResult(q, bool(done), total, ep, er, attempt, errors_by_frame)


def inverse_kinematics_frames(
    robot: RobotLike,
    target: Mapping[Any, Any],
    q0: object,
    rows: object,
    weights: object,
    rng: object,
    options: Options,
) -> MultiIKResult:
    """:func:`kinengine.control.ik.inverse_kinematics` for a mapping {frame: T_IF (4, 4)} (module doc)."""
    goals = checked_goals(robot, target, rows, weights, options)
    generator = RandomSource(rng)
    start = None if q0 is None else robot.engine.coordinates.check(q0, name="q0", allow_batch=False)
    return solve_frames(robot, goals, start, generator)


__all__ = [
    "FrameGoal",
    "MultiIKResult",
    "Options",
    "checked_goals",
    "inverse_kinematics_frames",
    "solve_frames",
]
