"""Inverse kinematics for a batch of targets (N, 4, 4), vectorized over every unconverged target at once.

The algorithm of :mod:`kinengine.control.ik` (same error, damping, seeds, attempts, give-up rule and
tolerances), each iteration done for all targets still running: poses and Jacobians J_e0 (N, 6, dof)
from the batch chain (:mod:`kinengine.kinematics.batch`), the rotation errors log(C_d Cᵀ) in closed
form, and the damped least-squares systems (N, m, m) solved by one ``np.linalg.solve``. A target
leaves the batch when it converges or runs out of attempts; one that gives up on an attempt moves to
its next seed while the others go on; the last ``TAIL`` stragglers finish on the single-target solver.
Its floating point differs from the single solver's (Pinocchio's Jacobian vs the batch chain's), so the
two agree in convergence and tolerance, not bit for bit.

The result is an :class:`IKBatchResult`: arrays over the batch (``q`` (N, dof), ``success`` (N,), ...),
and a sequence of N :class:`~kinengine.control.ik.IKResult` (``result[i]``, ``list(result)``).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..kinematics import batch
from .ik_seeds import SEED_ROTATION_WEIGHT, first_seeds
from .ik_solver import GIVE_UP, NULLSPACE_FADE, PROBE_ITERATIONS, IKResult, LimitWeights, solve_one
from .ik_target import Problem, RandomSource

if TYPE_CHECKING:  # the facade is a higher layer: named for the checker only
    from ..robot import Robot

TAIL = 16
"""When no more than this many targets are left running, each finishes on the single-target solver (one
target costs it ~20 numpy calls per iteration against ~150 for a batch iteration)."""


@dataclass(frozen=True)
class IKBatchResult:
    """N IK outcomes as arrays: q (N, dof) [rad | m] within the limits, success (N,), iterations (N,)
    (total per target), position_error (N,) [m], rotation_error (N,) [rad], restarts (N,) (attempts
    after the first). ``len(r)``, ``r[i]`` (an IKResult) and iteration over IKResults work too."""

    q: np.ndarray
    success: np.ndarray
    iterations: np.ndarray
    position_error: np.ndarray
    rotation_error: np.ndarray
    restarts: np.ndarray

    def __len__(self) -> int:
        return len(self.q)

    def __getitem__(self, i: int) -> IKResult:
        return IKResult(
            self.q[i].copy(),
            bool(self.success[i]),
            int(self.iterations[i]),
            float(self.position_error[i]),
            float(self.rotation_error[i]),
            int(self.restarts[i]),
        )

    def __iter__(self) -> Iterator[IKResult]:
        return (self[i] for i in range(len(self)))

    def __str__(self) -> str:
        return (
            f"IK batch: {int(self.success.sum())}/{len(self)} converged, "
            f"{int(self.iterations.sum())} iterations in all"
        )


def log3(R: np.ndarray) -> np.ndarray:
    """log of rotation matrices R (n, 3, 3) as rotation vectors (n, 3): θ = atan2(|w|/2, (tr R − 1)/2),
    w = vee(R − Rᵀ), log = θ·w/|w|; Pinocchio's log3 row by row where θ is within 0.15 rad of π."""
    w = np.stack((R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]), axis=1)
    norm = np.sqrt(np.einsum("ni,ni->n", w, w))
    cos = 0.5 * (R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2] - 1.0)
    theta = np.arctan2(0.5 * norm, cos)
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.where(norm > 1e-12, theta / norm, 0.5)
    out = w * factor[:, None]
    for i in np.flatnonzero(cos < -0.988):  # near π the axis from w is inaccurate
        out[i] = pin.log3(R[i])
    return out


def solve_batch(
    robot: Robot,
    problem: Problem,
    p_d: np.ndarray,
    C_d: np.ndarray,
    q0: np.ndarray | None,
    generator: RandomSource,
) -> IKBatchResult:
    """Solve every target (p_d (N, 3), C_d (N, 3, 3)) vectorized; see the module doc."""
    kin, joints, dof = robot.engine, robot.engine.coordinates, robot.dof
    n = len(p_d)
    seeds = first_seeds(robot, problem, p_d, C_d, q0)
    attempts = seeds.shape[1] + problem.restarts
    q = seeds[:, 0].copy()
    attempt, iteration, total = (np.zeros(n, dtype=np.intp) for _ in range(3))
    best_q, best = q.copy(), np.full((n, 3), np.inf)  # best score, ep, er
    best_attempt = np.zeros(n, dtype=np.intp)
    rows, sqrt_w, position_rows = problem.rows, problem.sqrt_weights, problem.position_rows
    tol_p, tol_r, max_iterations = problem.tol_position, problem.tol_rotation, problem.max_iterations
    lower, upper = joints.lower, joints.upper
    limits = LimitWeights(lower, upper)
    previous = np.full((n, dof), -1.0)  # |∂φ/∂q| at each target's last iteration (-1: none yet)
    active = np.arange(n)
    while len(active) > TAIL or (len(active) and len(active) == n):
        qa = np.ascontiguousarray(q[active])
        T, J = batch.evaluate(kin, qa, problem.fid, pin.LOCAL_WORLD_ALIGNED)
        assert T is not None and J is not None  # both asked for
        Cd = C_d[active]
        e = np.empty((len(active), 6))
        e[:, :3] = p_d[active] - T[:, :3, 3]
        e[:, 3:] = log3(Cd @ T[:, :3, :3].transpose(0, 2, 1))
        if rows is None:
            err = e
            ep, er = (
                np.sqrt(np.einsum("ni,ni->n", e[:, :3], e[:, :3])),
                np.sqrt(np.einsum("ni,ni->n", e[:, 3:], e[:, 3:])),
            )
        else:
            CdT = Cd.transpose(0, 2, 1)
            e_d = np.concatenate(
                (np.einsum("nij,nj->ni", CdT, e[:, :3]), np.einsum("nij,nj->ni", CdT, e[:, 3:])), axis=1
            )[:, rows]
            ep = np.sqrt(np.einsum("ni,ni->n", e_d[:, position_rows], e_d[:, position_rows]))
            er = np.sqrt(np.einsum("ni,ni->n", e_d[:, ~position_rows], e_d[:, ~position_rows]))
            err = e_d if sqrt_w is None else e_d * sqrt_w
        score = ep + SEED_ROTATION_WEIGHT * er
        it = iteration[active]
        done = (ep <= tol_p) & (er <= tol_r)
        last = attempt[active] == attempts - 1
        patient = last | ((attempt[active] == 0) & problem.patient_first)
        end = done | (it == max_iterations) | ((it == PROBE_ITERATIONS) & (score > GIVE_UP) & ~patient)
        if end.any():
            ended = active[end]
            total[ended] += it[end]
            better = score[end] < best[ended, 0]
            improved = ended[better]
            best_q[improved] = qa[end][better]
            best[improved] = np.column_stack((score[end][better], ep[end][better], er[end][better]))
            best_attempt[improved] = attempt[improved]
            again = ended[~(done[end] | last[end])]
            if len(again):  # next seed, then random configurations
                attempt[again] += 1
                iteration[again] = 0
                previous[again] = -1.0  # the first iteration of an attempt weights every joint
                seeded = attempt[again] < seeds.shape[1]
                q[again[seeded]] = seeds[again[seeded], attempt[again[seeded]]]
                if (~seeded).any():
                    q[again[~seeded]] = generator.configurations(robot, int((~seeded).sum()))
        step = ~end
        if step.any():
            J = J[step]
            err = err[step]
            if rows is not None:
                CdT = Cd[step].transpose(0, 2, 1)
                J = np.concatenate((CdT @ J[:, :3], CdT @ J[:, 3:]), axis=1)[:, rows]
                if sqrt_w is not None:
                    J = J * sqrt_w[:, None]
            moving = active[step]
            if limits.any:
                w, previous[moving] = limits.inverse_weights(q[moving], previous[moving])
            else:
                w = None
            q[moving] = _step(J, w, err, score[step], q[moving], problem)
            q[moving] = np.clip(q[moving], lower, upper)
            iteration[moving] += 1
        active = np.concatenate((active[step], again)) if end.any() else active
        active.sort()
    for i in active:  # the last few stragglers: the single-target solver, from their current attempt on
        a, S = int(attempt[i]), seeds.shape[1]
        rest = replace(
            problem,
            restarts=problem.restarts - (a - S) if a >= S else problem.restarts,
            patient_first=problem.patient_first and a == 0,
        )
        result = solve_one(
            robot, rest, p_d[i], C_d[i], seeds[i, a:] if a < S else seeds[i, :0], generator, wrap=False
        )
        total[i] += result.iterations
        score = result.position_error + SEED_ROTATION_WEIGHT * result.rotation_error
        if score < best[i, 0]:
            best_q[i], best[i] = result.q, (score, result.position_error, result.rotation_error)
            best_attempt[i] = a + result.restarts
    best_q[:, joints.continuous] = np.remainder(best_q[:, joints.continuous] + np.pi, 2 * np.pi) - np.pi
    success = (best[:, 1] <= tol_p) & (best[:, 2] <= tol_r)
    return IKBatchResult(best_q, success, total, best[:, 1].copy(), best[:, 2].copy(), best_attempt)


def _step(
    J: np.ndarray, w: np.ndarray | None, err: np.ndarray, score: np.ndarray, q: np.ndarray, problem: Problem
) -> np.ndarray:
    """q + Δq for every row: weighted damped least squares with λ² = ½|e|² + λ_min² (and the nullspace
    pull)."""
    JW = J if w is None else J * w[:, None, :]  # J W⁻¹
    A = JW @ J.transpose(0, 2, 1)
    JT = JW.transpose(0, 2, 1)
    m = A.shape[1]
    diagonal = A.reshape(len(A), m * m)[:, :: m + 1]
    diagonal += (0.5 * np.einsum("ni,ni->n", err, err) + problem.damping_sq)[:, None]
    if problem.q_ns is None:
        y = np.linalg.solve(A, err[..., None])
        return q + (JT @ y)[..., 0]
    z = (problem.gain * np.minimum(1.0, score / NULLSPACE_FADE))[:, None] * (problem.q_ns - q)
    y = np.linalg.solve(A, np.stack((err, (J @ z[..., None])[..., 0]), axis=2))
    return q + (JT @ (y[..., 0] - y[..., 1])[..., None])[..., 0] + z


__all__ = ["IKBatchResult", "log3", "solve_batch"]
