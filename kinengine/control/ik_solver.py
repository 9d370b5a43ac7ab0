"""The IK attempt loop, one for a single frame and for several: damped least squares iterations (see
:mod:`kinengine.control.ik` for the error and the seeds, :mod:`kinengine.control.ik_step` for the step, the
damping, the joint-limit weights and the give-way rule) from each seed in turn.

The frames' errors and Jacobians are stacked, e = (e_F1, e_F2, ...), J = (J_F1; J_F2; ...); a single target
is one frame. A full pose target is iterated in the frame F itself (e_F = blockdiag(Cᵀ, Cᵀ) e, J_F likewise,
Jacobian "local"): the step and the norms are the same in any frame (Robot Dynamics lecture notes, ETH
Zurich, §2.8), and the error comes from one SE3 call. Any other target keeps the rows S e [m, rad] of e in
I (a position or rotation part) or in the target frame D (``rows=``, S the kept rows of
blockdiag(C_dᵀ, C_dᵀ)), each times √w, with J_D = S J_e0 ("local_world_aligned")."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dposv  # 5x cheaper per call than np.linalg.solve on a 6x6

from . import ik_step as step
from .ik_seeds import SEED_ROTATION_WEIGHT
from .ik_target import FrameGoal, RandomSource

if TYPE_CHECKING:  # named for the checker only
    from .robot_like import RobotLike


@dataclass(frozen=True)
class IKResult:
    """Outcome of one IK solve: the best q found (dof,) [rad | m], within the limits."""

    q: np.ndarray
    success: bool
    iterations: int  # total over every attempt
    position_error: float  # |p_d − p| [m] over the kept position rows (0 if the position is free)
    rotation_error: float  # angle of C_d Cᵀ [rad] over the kept rotation rows (0 if the rotation is free)
    restarts: int  # attempts after the first one

    def __str__(self) -> str:
        state = "converged" if self.success else "did not converge"
        return (
            f"IK {state} after {self.iterations} iterations ({self.restarts} restarts): "
            f"position error {self.position_error:.3g} m, rotation error {self.rotation_error:.3g} rad"
        )


@dataclass(frozen=True)
class MultiIKResult(IKResult):
    """An :class:`IKResult` for several frames: position_error / rotation_error are the maxima over the
    frames, ``frame_errors`` {frame: (position error [m], rotation error [rad])} each frame's own."""

    frame_errors: dict[str, tuple[float, float]] | None = None


def _layout(goals: list[FrameGoal], err: np.ndarray) -> tuple[list[tuple], list[tuple], np.ndarray]:
    """Per frame, for its error: (fid, T_IF_d as an SE3 for a full pose else None, p_d, C_d, e (6,) [m, rad],
    S (k, 6) or None, √w or None, kept position rows, its rows start:stop of ``err``) (a full pose's e is
    its rows of ``err``, any other's rows are S e); for its Jacobian: (fid, reference frame, S·√w or None,
    start, stop); and the damping's row scale S⁻² (ik_step.POSE_ROW_DAMPING on a full pose's rows)."""
    errors: list[tuple] = []
    jacobians: list[tuple] = []
    row_damping, start = [], 0
    for g in goals:
        problem, p_d, C_d = g.problem, g.p_d, g.C_d
        fid, rows, sqrt_w, stop = problem.fid, problem.rows, problem.sqrt_weights, start + g.row_count
        if rows is None and p_d is not None and C_d is not None:  # a full pose, in F
            e = err[start:stop]
            errors.append((fid, pin.SE3(C_d, p_d), p_d, C_d, e, e[:3], e[3:], None, None, None, start, stop))
            jacobians.append((fid, pin.LOCAL, None, start, stop))
            row_damping.append(step.POSE_ROW_DAMPING)
        else:
            if rows is None:  # a position or rotation part, in I
                S = np.eye(6)[0 if p_d is not None else 3 : 6 if C_d is not None else 3]
            else:  # kept rows in D
                assert C_d is not None  # rows= is for pose targets only
                S = np.zeros((6, 6))
                S[:3, :3] = S[3:, 3:] = C_d.T
                S = np.ascontiguousarray(S[rows])
            S_w = S if sqrt_w is None else S * sqrt_w[:, None]
            position_rows = S[:, :3].any(axis=1)
            e = np.zeros(6)
            errors.append((fid, None, p_d, C_d, e, e[:3], e[3:], S, sqrt_w, position_rows, start, stop))
            jacobians.append((fid, pin.LOCAL_WORLD_ALIGNED, S_w, start, stop))
            row_damping.append(np.ones(stop - start))
        start = stop
    return errors, jacobians, row_damping[0] if len(goals) == 1 else np.concatenate(row_damping)


def solve(
    robot: RobotLike,
    goals: list[FrameGoal],
    seeds: np.ndarray,
    generator: RandomSource,
    several: bool = False,
) -> IKResult:
    """Attempts from each seed (S, dof), then ``restarts`` random ones; the first that brings every frame
    within the tolerances (or the best by Σ_F |e_p| + 0.2 m/rad·|e_R|) wins. ``several``: a
    :class:`MultiIKResult` (maxima over the frames and each frame's errors). Per iteration a dozen numpy
    calls on arrays of 6 to 42 numbers: their count sets the speed."""
    kin = robot.engine
    joints, model, data = kin.coordinates, kin.model, kin.data()
    shared = goals[0].problem
    tol_p, tol_r, max_iterations = shared.tol_position, shared.tol_rotation, shared.max_iterations
    damping_sq, q_ns, gain = shared.damping_sq, shared.q_ns, shared.gain
    attempts = len(seeds) + shared.restarts
    pinocchio_q, fold = kin.pinocchio_q, joints.fold
    # coordinates that move no frame left out; the others stepped in place in Pinocchio's q if one for one
    run = step.moving(kin, tuple(g.problem.fid for g in goals))
    cs, ps, free = run.coords, run.pin, run.free
    place, log3, get_jacobian = pin.updateFramePlacement, pin.log3, pin.getFrameJacobian
    # Pinocchio 4.1 crashes on a Jacobian with nv = 0: a robot without joints only has its pose computed
    movable = kin.dof > 0
    kinematics = pin.computeJointJacobians if movable else pin.forwardKinematics
    subtract, hypot, sqrt = np.subtract, math.hypot, math.sqrt
    m = sum(g.row_count for g in goals)
    err, J, A = np.empty(m), np.empty((m, cs.stop - cs.start)), np.empty(m * m)
    normal = (A.reshape(m, m), A[:: m + 1])  # A and its diagonal
    # a full pose's rows are weighted by S = diag(1, 1, 1, ρ, ρ, ρ): (S J W⁻¹Jᵀ S + λ² I) x = S e is
    # (J W⁻¹Jᵀ + λ² S⁻²)(S x) = e with Δq = W⁻¹Jᵀ (S x), so the weights only scale the damping's diagonal
    errors, jacobians, row_damping = _layout(goals, err)
    rotation_sq = step.ROTATION_ROW_WEIGHT**2
    weigh, bounds = run.limits.inverse_weights_one if run.limits.any else None, run.limits.bounds
    pull = None if q_ns is None else (q_ns[cs], shared.q_ns_within[free])  # type: ignore[index]
    best, total = None, 0
    for attempt in range(attempts):
        q = (seeds[attempt] if attempt < len(seeds) else generator.configurations(robot)).copy()
        if pull is not None:
            q[free] = pull[1]
        q_pin = pinocchio_q(q) if ps is not None else q  # q itself if Pinocchio's is q
        x = q_pin[ps] if ps is not None else q[cs]  # the stepped coordinates, a view
        from_q0 = attempt == 0 and shared.patient_first
        last = attempt == attempts - 1 or from_q0
        iteration, previous, lowest, since = 0, None, math.inf, 0
        history: list[float] = []  # the score at each iteration
        while True:
            kinematics(model, data, q_pin if ps is not None else pinocchio_q(q))
            per_frame = []
            score, squared, done = 0.0, 0.0, True
            for fid, target, p_d, C_d, e, e_p, e_r, S, sqrt_w, position_rows, start, stop in errors:
                M = place(model, data, fid)
                if target is not None:  # e in F: Cᵀ e = (Cᵀ(p_d − p), log3(Cᵀ C_d)) from M⁻¹ M_d
                    M = M.actInv(target)
                    e_p[:] = M.translation
                    e_r[:] = log3(M.rotation)
                    e0, e1, e2, e3, e4, e5 = e.tolist()
                    ep, er = hypot(e0, e1, e2), hypot(e3, e4, e5)
                    squared += e0 * e0 + e1 * e1 + e2 * e2 + rotation_sq * (e3 * e3 + e4 * e4 + e5 * e5)
                else:
                    if p_d is not None:
                        subtract(p_d, M.translation, out=e_p)
                    if C_d is not None:
                        e_r[:] = log3(C_d @ M.rotation.T)
                    e_d = S @ e
                    ep = sqrt(float(e_d[position_rows] @ e_d[position_rows]))
                    er = sqrt(float(e_d[~position_rows] @ e_d[~position_rows]))
                    kept = err[start:stop]
                    kept[:] = e_d if sqrt_w is None else e_d * sqrt_w
                    squared += float(kept @ kept)
                per_frame.append((ep, er))
                score += ep + SEED_ROTATION_WEIGHT * er
                done = done and ep <= tol_p and er <= tol_r
            if score < step.STUCK_RATIO * lowest:
                lowest, since = score, 0
            else:
                since += 1
            if (
                done
                or not movable  # no joint moves a frame: the error stays as it is
                or iteration == max_iterations
                or step.gives_way(iteration, score, history, last, since, from_q0)
            ):
                break
            history.append(score)
            iteration += 1
            for fid, reference, S_w, start, stop in jacobians:
                J_F = get_jacobian(model, data, fid, reference).reshape(6, -1)  # (6,) if nv = 1
                J_F = J_F[:, ps] if ps is not None else fold(J_F)[:, cs]
                if S_w is None:
                    J[start:stop] = J_F
                else:
                    np.dot(S_w, J_F, out=J[start:stop])
            diagonal = step.damping(squared, damping_sq) * row_damping
            nullspace = (None if pull is None else pull[0], gain, score)
            previous = step.take_step(x, J, err, normal, diagonal, weigh, previous, bounds, nullspace, dposv)
        q[cs] = x
        total += iteration
        if best is None or score < best[2]:
            best = (q, per_frame, score, attempt, done)
        if done:
            break
    assert best is not None  # attempts >= 1: the seeds hold at least one start
    q, per_frame, _, attempt, done = best
    run.limits.wrap(q[cs])  # the stepped coordinates' continuous joints into [-π, π)
    ep, er = max(pe[0] for pe in per_frame), max(pe[1] for pe in per_frame)
    if not several:
        return IKResult(q, bool(done), total, ep, er, attempt)
    by_frame = {g.problem.frame: pe for g, pe in zip(goals, per_frame, strict=True)}
    return MultiIKResult(q, bool(done), total, ep, er, attempt, by_frame)


__all__ = ["IKResult", "MultiIKResult", "solve"]
