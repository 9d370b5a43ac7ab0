"""The single-target IK solver: damped least squares iterations (see :mod:`kinengine.control.ik` for the
error, the step and the seeds) from each seed in turn, with Chan & Dubey's joint-limit weights
(:class:`LimitWeights`); returns an :class:`IKResult`.

Damping λ² = DAMPING_SCALE·|e|² + λ_min². An attempt other than the last gives way to the next seed when
its score |e_p| + 0.2 m/rad·|e_R| is still above GIVE_UP after PROBE_ITERATIONS iterations, or when, from
STALL_FROM iterations on, it has not fallen below STALL_RATIO × its value STALL_SPAN iterations earlier.
A full pose target is iterated in the frame F itself (e_F = blockdiag(Cᵀ, Cᵀ) e, J_F likewise): the step
and the norms are the same in any frame (Robot Dynamics lecture notes, ETH Zurich, §2.8)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from .ik_seeds import SEED_ROTATION_WEIGHT
from .ik_target import Problem, RandomSource

if TYPE_CHECKING:  # the facade is a higher layer: named for the checker only
    from ..kinematics.engine import Kinematics
    from ..robot import Robot

PROBE_ITERATIONS = 10
GIVE_UP = 1e-2
"""[m] score |e_p| + 0.2 m/rad·|e_R| above which an attempt gives way after PROBE_ITERATIONS iterations."""
STALL_FROM, STALL_SPAN, STALL_RATIO = 4, 3, 0.8
"""From iteration STALL_FROM on, an attempt whose score is above STALL_RATIO × its score STALL_SPAN iterations
earlier gives way (stuck on a joint limit or in a local minimum: such attempts crawl for max_iterations,
and on 1,000 random targets they cost the ABB IRB 120 more iterations than the converging ones)."""
DAMPING_SCALE = 0.1
"""λ² = DAMPING_SCALE·|e|² + λ_min² (Sugihara's rule λ² = ½ eᵀW_E e + λ_min² with W_E = 0.2·I, e weighted as
below): weaker than ½|e|², so the first steps from a stored seed go further."""
ROTATION_ROW_WEIGHT = SEED_ROTATION_WEIGHT
"""[m/rad] a full pose's rotation rows (error and Jacobian) are weighted by this in the least squares, which
then minimizes |e_p|² + (0.2 m/rad·|e_R|)², the squared pose distance that ranks attempts and seeds
(the step is Δq = W⁻¹Jᵀ (J W⁻¹Jᵀ + λ² S⁻²)⁻¹ e, S = diag(1, 1, 1, ρ, ρ, ρ)). With the stall rule and
DAMPING_SCALE 0.1, against unweighted rows, ½|e|² and no stall rule, on 3 x 1,000 random targets
(rng 31-33): 7.2 instead of 15.9 mean iterations on the ABB IRB 120 (UR5 7.9 / 15.8, Panda arm
8.6 / 15.4), successes 3000, 2998, 2995 instead of 3000, 2996, 2993."""
NULLSPACE_FADE = 5e-2
"""[m] the nullspace pull is gain · min(1, score / this): full strength far from the target, fading with
the error so that its second-order effect on the task (∝ |z|²) vanishes and the solve converges."""


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


class LimitWeights:
    """Chan & Dubey's weighted least norm: w_i = 1 + |∂φ/∂q_i| while joint i approaches a limit (|∂φ/∂q_i|
    grew since the last iteration), else 1, with φ = Σ (u−l)² / (4 (u−q)(q−l)), so
    ∂φ/∂q = (u−l)² (2q − u − l) / (4 (u−q)² (q−l)²); unbounded joints: 1.
    ``continuous`` (dof,) bool, optional: kept as the indices of the joints a solution wraps into [-π, π)
    (None if there are none)."""

    def __init__(self, lower: np.ndarray, upper: np.ndarray, continuous: np.ndarray | None = None) -> None:
        self.bounded = np.isfinite(lower) & np.isfinite(upper)
        self.any = bool(self.bounded.any())
        self.lower, self.upper = np.where(self.bounded, lower, -1.0), np.where(self.bounded, upper, 1.0)
        self.middle_twice = self.lower + self.upper
        self.quarter_span_sq = np.where(self.bounded, self.upper - self.lower, 0.0) ** 2 / 4  # 0: unbounded
        columns = (self.lower, self.upper, self.middle_twice, self.quarter_span_sq)
        self._rows = np.column_stack(columns).tolist()  # per joint (l, u, l + u, (u − l)²/4)
        self.continuous = np.flatnonzero(continuous) if continuous is not None and continuous.any() else None

    def wrap(self, q: np.ndarray) -> None:
        """The continuous joints' angles of q (dof,) or (n, dof) into [-π, π), in place."""
        turns = self.continuous
        if turns is not None:
            q[..., turns] = np.remainder(q[..., turns] + np.pi, 2 * np.pi) - np.pi

    def inverse_weights(self, q: np.ndarray, previous: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(1 / w, |∂φ/∂q|) for columns q (dof, r) (one configuration a column, the batched solver's layout),
        given |∂φ/∂q| of the last iteration (dof, r) (−1 where there is none: every joint weighted).
        Distances to the limits are floored at 1e-12 (a joint on its limit gets a huge finite gradient,
        weight ~0)."""
        lower, upper = self.lower[:, None], self.upper[:, None]
        distances = np.maximum(upper - q, 1e-12) * np.maximum(q - lower, 1e-12)
        spread = np.abs(2 * q - self.middle_twice[:, None])
        grad = self.quarter_span_sq[:, None] * spread / (distances * distances)
        return np.where(grad > previous, 1.0 / (1.0 + grad), 1.0), grad

    def inverse_weights_one(self, q: np.ndarray, previous: list | None) -> tuple[np.ndarray, list]:
        """:meth:`inverse_weights` for one q (dof,) in plain floats (a dozen numpy calls on a 6-vector cost
        more than the arithmetic); ``previous`` and the returned gradient are lists."""
        grad: list[float] = []
        append = grad.append
        for qi, (lo, hi, mid2, quarter) in zip(q.tolist(), self._rows, strict=True):
            du, dl = hi - qi, qi - lo
            d = (du if du > 1e-12 else 1e-12) * (dl if dl > 1e-12 else 1e-12)
            append(quarter * abs(2.0 * qi - mid2) / (d * d))
        if previous is None:
            return np.array([1.0 / (1.0 + g) for g in grad]), grad
        inverse = [1.0 / (1.0 + g) if g > p else 1.0 for g, p in zip(grad, previous, strict=True)]
        return np.array(inverse), grad


def limit_weights(kin: Kinematics) -> LimitWeights:
    """The robot's LimitWeights (its coordinates' limits and continuous joints), made once per robot."""
    c = kin.coordinates
    return kin.memoized("ik limit weights", lambda: LimitWeights(c.lower, c.upper, c.continuous))


def gives_way(iteration: int, score: float, history: list[float]) -> bool:
    """Whether an attempt other than the last makes way for the next seed at this iteration (its score
    still above GIVE_UP after PROBE_ITERATIONS, or stalled: see STALL_FROM); ``history``: earlier scores."""
    return (iteration == PROBE_ITERATIONS and score > GIVE_UP) or (
        iteration >= STALL_FROM and score > STALL_RATIO * history[iteration - STALL_SPAN]
    )


def take_step(
    q: np.ndarray,
    J: np.ndarray,
    err: np.ndarray,
    A: np.ndarray,
    damping: np.ndarray | float,
    weigh: Callable[[np.ndarray, list | None], tuple[np.ndarray, list]] | None,
    previous: list | None,
    bounds: tuple[np.ndarray, np.ndarray],
    nullspace: tuple[np.ndarray | None, float, float],
    dposv: Callable[..., tuple],
) -> list | None:
    """One damped, limit-weighted step in place: q ← clip(q + W⁻¹Jᵀ A⁻¹ e (+ z), lower, upper) with
    A = J W⁻¹Jᵀ + diag(damping) written into the (m, m) buffer ``A`` and solved by Cholesky (``dposv``; least
    squares where it is not positive definite). ``weigh``: LimitWeights.inverse_weights_one (None: W = I),
    ``previous`` its last gradient, which is returned for the next step. ``nullspace`` (q_ns, gain, score):
    the pull z towards q_ns (None: none)."""
    JW = J
    if weigh is not None:
        w, previous = weigh(q, previous)
        JW = J * w
    np.dot(JW, J.T, out=A)
    A.reshape(-1)[:: len(A) + 1] += damping
    q_ns, gain, score = nullspace
    if q_ns is None:
        _, x, info = dposv(A, err)
        q += np.dot(JW.T, x if info == 0 else np.linalg.lstsq(A, err, rcond=None)[0])
    else:
        z = (gain * min(1.0, score / NULLSPACE_FADE)) * (q_ns - q)
        b = np.column_stack((err, J @ z))
        _, x, info = dposv(A, b)
        if info:
            x = np.linalg.lstsq(A, b, rcond=None)[0]
        q += JW.T @ (x[:, 0] - x[:, 1]) + z
    np.minimum(np.maximum(q, bounds[0], out=q), bounds[1], out=q)
    return previous


def solve_one(
    robot: Robot,
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
    rotation_sq = ROTATION_ROW_WEIGHT**2 if full else 1.0
    row_damping = np.array([1.0, 1.0, 1.0] + [1.0 / rotation_sq] * 3) if full else 1.0
    subtract, hypot = np.subtract, math.hypot
    m = len(rows) if rows is not None else part.stop - part.start
    A = np.empty((m, m))
    limits = limit_weights(kin)
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
            if done or iteration == max_iterations or (not last and gives_way(iteration, score, history)):
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
            damping = (DAMPING_SCALE * squared + damping_sq) * row_damping
            previous = take_step(q, J, err, A, damping, weigh, previous, bounds, (q_ns, gain, score), dposv)
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


__all__ = [
    "DAMPING_SCALE",
    "GIVE_UP",
    "NULLSPACE_FADE",
    "PROBE_ITERATIONS",
    "ROTATION_ROW_WEIGHT",
    "STALL_FROM",
    "STALL_RATIO",
    "STALL_SPAN",
    "IKResult",
    "LimitWeights",
    "gives_way",
    "limit_weights",
    "solve_one",
    "take_step",
]
