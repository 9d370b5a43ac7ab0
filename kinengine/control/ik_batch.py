"""Inverse kinematics for a batch of targets (N, 4, 4), vectorized over every running attempt at once.

The algorithm of :mod:`kinengine.control.ik` (same error, damping, limit weights, seeds, attempts,
give-up rules and tolerances), each iteration done for every attempt still running, held column-wise
(q (dof, r), J (6, dof, r), ...: every numpy call runs over r contiguous entries): poses and
Jacobians J_e0 from the batch chain (:mod:`kinengine.kinematics.batch`, written straight into reused
column buffers), the rotation errors log(C_d Cᵀ) in closed form, and the damped least-squares systems
(m, m, r) by a column-wise Cholesky factorization (LAPACK for few columns). Attempts that end
(converged, given up, out of iterations) are compacted away, and the target's next attempt starts (its
seed looked up only then: :class:`~kinengine.control.ik_seeds.BatchSeeds`). When few attempts are left
running (SPECULATE), each target runs several of its next attempts at the same time; every target's
outcome is then taken from its attempts in order (:func:`_resolve`): the same q, success, iteration
count and restarts as if the attempts had run one after another. The last few attempts that never give
way (TAIL) are rerun from their starts by the single solver. Floating point differs from the single
solver's (the batch chain's Jacobian, Cholesky), so the two agree in convergence and tolerance, not bit
for bit; random restarts draw from ``rng`` in a different order.

The result is an :class:`IKBatchResult`: arrays over the batch (``q`` (N, dof), ``success`` (N,), ...),
and a sequence of N :class:`~kinengine.control.ik.IKResult` (``result[i]``, ``list(result)``).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..kinematics import batch
from . import ik_solver as rules  # the single solver's constants, followed here
from .ik_seeds import SEED_ROTATION_WEIGHT, BatchSeeds
from .ik_solver import IKResult, LimitWeights, limit_weights, solve_one
from .ik_target import Problem, RandomSource

if TYPE_CHECKING:  # the facade is a higher layer: named for the checker only
    from ..robot import Robot

TAIL = 4
"""When no more columns than this are left, all of them attempts that never give way (the last ones), the
single-target solver runs each again from its start (~15 µs an iteration, a batch iteration ~125 µs)."""
LAPACK_BELOW = 256
"""Fewer columns than this solve their damped systems by np.linalg.solve, more by the column-wise Cholesky."""
SPECULATE = 1024
"""When no more attempts than this are running, targets run their next ones at the same time (up to this
many in all): a batch iteration costs about the same for one column as for a few hundred."""
CHUNK_TARGETS = 65536
"""Larger batches are solved in chunks of this many targets (bounded buffers: ~1.6 KiB a target)."""


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


def solve_batch(
    robot: Robot, problem: Problem, p_d: np.ndarray, C_d: np.ndarray, q0: np.ndarray | None, rng: RandomSource
) -> IKBatchResult:
    """Solve every target (p_d (N, 3), C_d (N, 3, 3)) vectorized; see the module doc."""
    kin, joints, dof, n, c = robot.engine, robot.engine.coordinates, robot.dof, len(p_d), CHUNK_TARGETS
    if n > c:  # q0 (N, dof) split with the targets, q0 (dof,) shared
        cut = [slice(a, a + c) for a in range(0, n, c)]
        Q0 = [q0 if q0 is None or q0.ndim == 1 else q0[k] for k in cut]
        parts = [solve_batch(robot, problem, p_d[k], C_d[k], q, rng) for k, q in zip(cut, Q0, strict=True)]
        return IKBatchResult(*(np.concatenate([getattr(x, f.name) for x in parts]) for f in fields(parts[0])))
    seeds = BatchSeeds(robot, problem, p_d, C_d, q0)
    attempts = seeds.count + problem.restarts
    rows, sqrt_w, position_rows = problem.rows, problem.sqrt_weights, problem.position_rows
    tol_p, tol_r, max_iterations = problem.tol_position, problem.tol_rotation, problem.max_iterations
    lower, upper = joints.lower[:, None], joints.upper[:, None]
    limits = limit_weights(robot.engine)
    winner = np.full(n, attempts, dtype=np.intp)  # each target's first converged attempt (none yet)
    launched = np.zeros(n, dtype=np.intp)  # attempts started so far
    log: list[tuple[np.ndarray, ...]] = []  # every finished attempt: target, attempt, iterations, ...
    # one column per running attempt, compacted as they end: (target, attempt, iterations so far) and
    # rows q (dof), |∂φ/∂q| at the last iteration (dof; -1: none yet), the scores of the last STALL_SPAN
    # iterations (newest first), the target's p_d (3) and C_d (9), the attempt's start (dof)
    H, P, S = 2 * dof, 2 * dof + rules.STALL_SPAN, 2 * dof + rules.STALL_SPAN + 12  # history, p_d, start
    meta, state = np.empty((3, 0), dtype=np.intp), np.empty((S + dof, 0))
    space = _Workspace(max(n, SPECULATE), dof)
    new = np.arange(n)
    while True:
        if len(new):  # start the next attempt of these targets (np.repeat-ed for several at once)
            new_meta = np.stack((new, launched[new], np.zeros(len(new), dtype=np.intp)))
            new_meta[1] += np.arange(len(new)) - np.searchsorted(new, new)  # several of one target
            np.maximum.at(launched, new, new_meta[1] + 1)
            block = np.empty((len(state), len(new)))
            seeded = new_meta[1] < seeds.count
            block[:dof, seeded] = seeds.starts(new[seeded], new_meta[1][seeded]).T
            if (~seeded).any():
                block[:dof, ~seeded] = rng.configurations(robot, int((~seeded).sum())).T
            block[dof:H], block[S:] = -1.0, block[:dof]
            block[P : P + 3], block[P + 3 : S] = p_d[new].T, C_d[new].reshape(-1, 9).T
            meta, state = np.concatenate((meta, new_meta), axis=1), np.concatenate((state, block), axis=1)
        r, (tid, att, it) = meta.shape[1], meta
        patient = (att == attempts - 1) | ((att == 0) & problem.patient_first)
        if r <= TAIL and patient.all():  # a few attempts that never give way: the single solver reruns them
            rest = replace(problem, restarts=0, patient_first=True)
            tail = [
                solve_one(robot, rest, p_d[t], C_d[t], x[None], rng)
                for t, x in zip(tid, state[S:].T.copy(), strict=True)
            ]
            e = np.array([[o.position_error, o.rotation_error, o.iterations] for o in tail]).reshape(r, 3).T
            q_t = np.array([o.q for o in tail]).reshape(r, dof)
            log.append((tid, att, e[2].astype(np.intp), e[0] + SEED_ROTATION_WEIGHT * e[1], e[0], e[1], q_t))
            np.minimum.at(winner, tid, np.where([o.success for o in tail], att, attempts))
            break
        if r > space.capacity:
            space = _Workspace(r, dof)
        q, history, pd, Cd = state[:dof], state[H:P], state[P : P + 3], state[P + 3 : S].reshape(3, 3, r)
        T, J = space.pose[..., :r], space.jac[..., :r]  # (4, 4, r), (6, dof, r): the chain writes rows
        batch.evaluate(
            kin, q.T, problem.fid, pin.LOCAL_WORLD_ALIGNED, out=(T.transpose(2, 0, 1), J.transpose(2, 0, 1))
        )
        e = np.empty((6, r))
        np.subtract(pd, T[:3, 3], out=e[:3])
        _log3_columns(Cd, T[:3, :3], e[3:])
        if rows is None:
            err, (ep, er) = e, np.sqrt(np.einsum("kin,kin->kn", e.reshape(2, 3, r), e.reshape(2, 3, r)))
        else:
            e_d = np.einsum("kin,jkn->jin", Cd, e.reshape(2, 3, r)).reshape(6, r)[rows]  # C_dᵀ e, blockwise
            ep = np.sqrt(np.einsum("in,in->n", e_d[position_rows], e_d[position_rows]))
            er = np.sqrt(np.einsum("in,in->n", e_d[~position_rows], e_d[~position_rows]))
            err = e_d if sqrt_w is None else e_d * sqrt_w[:, None]
        score = ep + SEED_ROTATION_WEIGHT * er
        done = (ep <= tol_p) & (er <= tol_r)
        stalled = (it >= rules.STALL_FROM) & (score > rules.STALL_RATIO * history[-1])  # STALL_SPAN earlier
        gives_way = ((it == rules.PROBE_ITERATIONS) & (score > rules.GIVE_UP) | stalled) & ~patient
        end = done | (it == max_iterations) | gives_way
        history[1:], history[0] = history[:-1].copy(), score  # newest first
        ended = np.empty(0, dtype=np.intp)
        if end.any():
            log.append((tid[end], att[end], it[end], score[end], ep[end], er[end], q[:, end].T))
            np.minimum.at(winner, tid[end & done], att[end & done])
            ended = tid[end & ~done]
            keep = ~end & (att < winner[tid])  # attempts after a converged one are dropped
            meta, state, err, score = meta[:, keep], state[:, keep], err[:, keep], score[keep]
            J, r = space.compact(J, keep), len(score)
            tid, q, Cd = meta[0], state[:dof], state[P + 3 : S].reshape(3, 3, r)
        if r:
            if rows is not None:
                J = np.einsum("kin,hkjn->hijn", Cd, J.reshape(2, 3, dof, r)).reshape(6, dof, r)
                J = J[rows] if sqrt_w is None else J[rows] * sqrt_w[:, None, None]
            w = None
            if limits.any:
                w, state[dof:H] = limits.inverse_weights(q, state[dof:H])
            np.clip(_step(J, w, err, score, q, problem, space), lower, upper, out=q)
            meta[2] += 1
        # next attempts: one per target that needs one; when few columns run, several at once per target
        # (_resolve takes the outcomes in attempt order, as if the attempts had run one after another)
        if not end.any():  # no attempt ended: nothing new to start
            new = ended
            continue
        speculate = r + len(ended) <= SPECULATE
        candidates = np.unique(np.concatenate((tid, ended)) if speculate else ended)
        running = np.bincount(tid, minlength=n)[candidates]
        share = max(1, SPECULATE // max(1, len(candidates))) if speculate else 1
        extra = np.minimum(share - running, attempts - launched[candidates])
        extra[winner[candidates] < attempts] = 0
        new = np.repeat(candidates, np.maximum(extra, 0))
    return _resolve(log, winner, limits, (tol_p, tol_r))


def _resolve(
    log: list[tuple[np.ndarray, ...]], winner: np.ndarray, limits: LimitWeights, tol: tuple
) -> IKBatchResult:
    """Each target's outcome from its finished attempts, as the single solver takes them one after
    another: the attempts up to the first converged one count (iterations summed), and the best score
    among them wins (the earliest on a tie)."""
    tid, att, it, score, ep, er, q = (np.concatenate(column) for column in zip(*log, strict=True))
    counted = att <= winner[tid]
    tid, att, it, score, ep, er, q = (a[counted] for a in (tid, att, it, score, ep, er, q))
    total = np.bincount(tid, weights=it, minlength=len(winner)).astype(np.intp)
    order = np.lexsort((att, score, tid))
    first = order[np.r_[True, tid[order][1:] != tid[order][:-1]]]  # best per target, targets ascending
    best_q = q[first]
    limits.wrap(best_q)
    success = (ep[first] <= tol[0]) & (er[first] <= tol[1])
    return IKBatchResult(best_q, success, total, ep[first], er[first], att[first])


def _log3_columns(Cd: np.ndarray, C: np.ndarray, out: np.ndarray) -> None:
    """log(C_d Cᵀ) (3, r) into ``out`` for columns of rotations Cd, C (3, 3, r): θ = atan2(|w|/2, (tr − 1)/2),
    log = θ·w/|w| with w = vee(C_d Cᵀ − C C_dᵀ) = Σ_k c_k × d_k (c_k, d_k the k-th columns of C and C_d) and
    tr(C_d Cᵀ) = Σ C_d∘C; Pinocchio's log3 column by column where θ is within 0.15 rad of π."""
    roll, back = [1, 2, 0], [2, 0, 1]
    w = np.einsum("ikn,ikn->in", Cd[back], C[roll]) - np.einsum("ikn,ikn->in", Cd[roll], C[back])
    norm = np.sqrt(np.einsum("in,in->n", w, w))
    cos = 0.5 * (np.einsum("ikn,ikn->n", Cd, C) - 1.0)
    theta = np.arctan2(0.5 * norm, cos)
    with np.errstate(divide="ignore", invalid="ignore"):
        np.multiply(w, np.where(norm > 1e-12, theta / norm, 0.5), out=out)
    for i in np.flatnonzero(cos < -0.988).tolist():  # near π the axis from w is inaccurate
        out[:, i] = pin.log3(Cd[..., i] @ C[..., i].T)


class _Workspace:
    """Buffers for up to ``capacity`` columns reused from iteration to iteration (fresh arrays of a few MiB
    cost a page fault per 4 KiB): poses, two Jacobians (compacted one into the other), J W⁻¹ and A."""

    def __init__(self, capacity: int, dof: int) -> None:
        self.capacity, self.pose = capacity, np.empty((4, 4, capacity))
        self.jac, self.spare = np.empty((6, dof, capacity)), np.empty((6, dof, capacity))
        self.weighted, self.normal = np.empty((6, dof, capacity)), np.empty((6, 6, capacity))

    def compact(self, J: np.ndarray, keep: np.ndarray) -> np.ndarray:
        """J's kept columns, in the spare Jacobian buffer (which becomes the next iteration's)."""
        out = np.compress(keep, J, axis=2, out=self.spare[..., : int(keep.sum())])
        self.jac, self.spare = self.spare, self.jac
        return out


def _step(
    J: np.ndarray,
    w: np.ndarray | None,
    err: np.ndarray,
    score: np.ndarray,
    q: np.ndarray,
    problem: Problem,
    space: _Workspace,
) -> np.ndarray:
    """q + Δq for every column (J (m, dof, r), err (m, r), q (dof, r)): weighted damped least squares
    (and the nullspace pull) as the single solver's, A = J W⁻¹ Jᵀ + λ² I by Cholesky."""
    m, r = len(J), J.shape[2]
    JW = J if w is None else np.multiply(J, w, out=space.weighted[:m, :, :r])  # J W⁻¹
    A = space.normal[:m, :m, :r]
    if r < LAPACK_BELOW:
        np.einsum("ikn,jkn->ijn", JW, J, out=A)
    else:  # the lower triangle only: the Cholesky factorization reads no more
        for i in range(m):
            np.einsum("kn,jkn->jn", JW[i], J[: i + 1], out=A[i, : i + 1])
    # a full pose's rotation rows weighted by ρ = ROTATION_ROW_WEIGHT (as the single solver): λ² =
    # DAMPING_SCALE·(|e_p|² + ρ²|e_R|²) + λ_min², and A's diagonal takes λ²·(1, 1, 1, ρ⁻², ρ⁻², ρ⁻²)
    rho = rules.ROTATION_ROW_WEIGHT if problem.rows is None else 1.0
    squared = np.einsum("in,in->n", err, err)
    if rho != 1.0:
        squared += (rho**2 - 1.0) * np.einsum("in,in->n", err[3:], err[3:])
    damping = rules.DAMPING_SCALE * squared + problem.damping_sq
    for i in range(len(A)):
        A[i, i] += damping if i < 3 else damping / rho**2
    z = None
    if problem.q_ns is not None:
        z = (problem.gain * np.minimum(1.0, score / rules.NULLSPACE_FADE)) * (problem.q_ns[:, None] - q)
        err = err - np.einsum("ijn,jn->in", J, z)
    if r < LAPACK_BELOW:  # LAPACK per (m, m) system: ~1 µs each, against ~80 µs of calls for Cholesky
        y = np.linalg.solve(A.transpose(2, 0, 1), err.T[..., None])[..., 0].T
    else:
        y = _cholesky_solve(A, err)
    return q + np.einsum("ijn,in->jn", JW, y) + (0.0 if z is None else z)


def _cholesky_solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """x with A x = b for columns of symmetric positive definite A (m, m, r), b (m, r): A = L Lᵀ (L
    overwrites A's lower triangle), then the two triangular solves, each step over every column at once
    (pivots floored at 1e-300)."""
    m, L = len(A), A
    inverse = np.empty_like(b)  # 1 / L_jj
    for j in range(m):
        pivot = A[j, j] - np.einsum("kn,kn->n", L[j, :j], L[j, :j]) if j else A[j, j]
        inverse[j] = 1.0 / np.sqrt(np.maximum(pivot, 1e-300))
        if j + 1 < m:
            column = A[j + 1 :, j] - np.einsum("ikn,kn->in", L[j + 1 :, :j], L[j, :j]) if j else A[1:, 0]
            L[j + 1 :, j] = column * inverse[j]
    x = np.empty_like(b)  # y of L y = b, then overwritten from the bottom up by x of Lᵀ x = y
    for i in range(m):
        x[i] = (b[i] - np.einsum("kn,kn->n", L[i, :i], x[:i]) if i else b[i]) * inverse[i]
    for i in range(m - 1, -1, -1):
        if i + 1 < m:
            x[i] = (x[i] - np.einsum("kn,kn->n", L[i + 1 :, i], x[i + 1 :])) * inverse[i]
        else:
            x[i] *= inverse[i]
    return x


__all__ = ["IKBatchResult", "solve_batch"]
