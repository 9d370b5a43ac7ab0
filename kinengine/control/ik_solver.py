"""The single-target IK solver: damped least squares iterations (see :mod:`kinengine.control.ik` for the
error and the seeds, :mod:`kinengine.control.ik_step` for the step, the damping, the joint-limit weights and
the give-way rule) from each seed in turn; returns an :class:`IKResult`.

A full pose target is iterated in the frame F itself (e_F = blockdiag(Cᵀ, Cᵀ) e, J_F likewise): the step
and the norms are the same in any frame (Robot Dynamics lecture notes, ETH Zurich, §2.8)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from . import ik_step as step
from .ik_seeds import SEED_ROTATION_WEIGHT
from .ik_target import Problem, RandomSource

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


def solve_one(
    robot: RobotLike,
    problem: Problem,
    p_d: np.ndarray | None,
    C_d: np.ndarray | None,
    seeds: np.ndarray,
    generator: RandomSource,
    wrap: bool = True,
) -> IKResult:
    """Attempts from each seed, then ``restarts`` random ones; the first converged (or the best) wins.

    Per iteration a dozen numpy calls on arrays of 6 to 42 numbers, so their count sets the speed: the
    normal matrix is written into one buffer whose diagonal view takes λ², and solved by Cholesky
    (LAPACK ``dposv``: J W⁻¹Jᵀ + λ² I is symmetric positive definite for λ > 0; least squares if not)."""
    from scipy.linalg.lapack import dposv  # 5x cheaper per call than np.linalg.solve on a 6x6

    kin = robot.engine
    joints = kin.coordinates
    model, data = kin.model, kin.data()
    lower, upper, fid = joints.lower, joints.upper, problem.fid
    tol_p, tol_r, max_iterations = problem.tol_position, problem.tol_rotation, problem.max_iterations
    rows, sqrt_w, position_rows = problem.rows, problem.sqrt_weights, problem.position_rows
    damping_sq, q_ns, gain = problem.damping_sq, problem.q_ns, problem.gain
    attempts = len(seeds) + problem.restarts
    e = np.zeros(6)
    e_p, e_r = e[:3], e[3:]
    full = rows is None and p_d is not None and C_d is not None
    part = slice(0 if p_d is not None else 3, 6 if C_d is not None else 3)
    pinocchio_q, fold, identity = kin.pinocchio_q, joints.fold, joints.identity
    frame_jacobian, place, log3, LWA = (
        pin.computeFrameJacobian,
        pin.updateFramePlacement,
        pin.log3,
        pin.LOCAL_WORLD_ALIGNED,
    )
    joint_jacobians, get_jacobian, LOCAL = pin.computeJointJacobians, pin.getFrameJacobian, pin.LOCAL
    forward, movable = pin.forwardKinematics, kin.dof > 0  # Pinocchio 4.1 crashes on a Jacobian with nv = 0
    # A full pose is solved in F (the damped step and the norms do not depend on the frame they are
    # written in): its error then comes from one SE3 call instead of a subtraction and a 3x3 product.
    target = pin.SE3(C_d, p_d) if full else None
    # Rows weighted by S = diag(1, 1, 1, ρ, ρ, ρ): (S J W⁻¹Jᵀ S + λ² I) x = S e is (J W⁻¹Jᵀ + λ² S⁻²)(S x) = e
    # with Δq = W⁻¹Jᵀ (S x): the weights only scale the damping on the diagonal.
    rotation_sq = step.ROTATION_ROW_WEIGHT**2 if full else 1.0
    row_damping = step.POSE_ROW_DAMPING if full else 1.0
    subtract, hypot = np.subtract, math.hypot
    m = len(rows) if rows is not None else part.stop - part.start
    A = np.empty((m, m))
    limits = step.limit_weights(kin)
    weigh = limits.inverse_weights_one if limits.any else None
    bounds = (lower, upper)
    best, total = None, 0
    for attempt in range(attempts):
        q = (seeds[attempt] if attempt < len(seeds) else generator.configurations(robot)).copy()
        last = attempt == attempts - 1 or (attempt == 0 and problem.patient_first)
        iteration, previous = 0, None
        history: list[float] = []  # the score at each iteration
        while True:
            qp = q if identity else pinocchio_q(q)
            if full:  # e and J in F: Cᵀ e = (Cᵀ(p_d − p), log3(Cᵀ C_d)) from M⁻¹ M_d, one SE3 call
                (joint_jacobians if movable else forward)(model, data, qp)
                M = place(model, data, fid).actInv(target)
                e_p[:] = M.translation
                e_r[:] = log3(M.rotation)
            else:
                if movable:
                    J = frame_jacobian(model, data, qp, fid, LWA)
                else:
                    forward(model, data, qp)
                M = place(model, data, fid)
                if p_d is not None:
                    subtract(p_d, M.translation, out=e_p)
                if C_d is not None:
                    e_r[:] = log3(C_d @ M.rotation.T)
            if rows is None:
                e0, e1, e2, e3, e4, e5 = e.tolist()
                ep, er = hypot(e0, e1, e2), hypot(e3, e4, e5)
                err = e if full else e[part]
                squared = e0 * e0 + e1 * e1 + e2 * e2 + rotation_sq * (e3 * e3 + e4 * e4 + e5 * e5)
            else:
                assert C_d is not None  # rows= is for pose targets only
                e_d = np.concatenate((C_d.T @ e_p, C_d.T @ e_r))[rows]
                ep = math.sqrt(float(e_d[position_rows] @ e_d[position_rows]))
                er = math.sqrt(float(e_d[~position_rows] @ e_d[~position_rows]))
                err = e_d if sqrt_w is None else e_d * sqrt_w
                squared = float(err @ err)
            score = ep + SEED_ROTATION_WEIGHT * er
            done = ep <= tol_p and er <= tol_r
            if (
                done
                or iteration == max_iterations
                or (not last and step.gives_way(iteration, score, history))
            ):
                break
            if not movable:  # no joint moves the frame: the error stays as it is
                break
            history.append(score)
            iteration += 1
            if full:
                J = get_jacobian(model, data, fid, LOCAL)
            if not identity or J.ndim == 1:
                J = fold(J.reshape(6, -1))
            if rows is not None:
                assert C_d is not None
                J = np.vstack((C_d.T @ J[:3], C_d.T @ J[3:]))[rows]
                if sqrt_w is not None:
                    J = J * sqrt_w[:, None]
            elif not full:
                J = J[part]
            diagonal = step.damping(squared, damping_sq) * row_damping
            previous = step.take_step(
                q, J, err, A, diagonal, weigh, previous, bounds, (q_ns, gain, score), dposv
            )
        total += iteration
        if best is None or score < best[3]:
            best = (q, ep, er, score, attempt)
        if done:
            break
    assert best is not None  # attempts >= 1: the seeds hold at least one start
    q, ep, er, _, attempt = best
    if wrap:
        limits.wrap(q)
    return IKResult(q, bool(ep <= tol_p and er <= tol_r), total, ep, er, attempt)


__all__ = ["IKResult", "solve_one"]
