"""Inverse kinematics for a batch of targets (N, 4, 4): the algorithm of :mod:`kinengine.control.ik` (same
error, damping, limit weights, seeds, attempts, give-way rules, tolerances) run for every running attempt
at once, held column-wise (q (dof, r), J (6, dof, r): each numpy call runs over r contiguous entries).
Poses and Jacobians J_e0 come from the batch chain (:mod:`kinengine.kinematics.batch`, into reused
buffers), log(C_d Cᵀ) from the rotation-vector parameterization, the step from :func:`.ik_step.take_steps`.
Ended attempts are compacted away and the target's next one starts (its seed looked up only then,
:class:`.ik_seeds.BatchSeeds`); with few left running (SPECULATE) a target runs several next attempts at
once, and :func:`_resolve` takes the outcomes in attempt order: the same q, success, iterations and
restarts as one after another. Floating point differs from :func:`.ik_solver.solve`'s (the Jacobian in I,
another factorization): the two agree in convergence and tolerance, not bit for bit; random restarts draw
from ``rng`` in another order. The result, an :class:`IKBatchResult`, holds arrays over the batch and is a
sequence of N :class:`~kinengine.control.ik.IKResult`.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..kinematics import batch
from ..parameterizations import ROTATION_PARAMETERIZATIONS
from . import ik_step as step
from .ik_seeds import SEED_ROTATION_WEIGHT, BatchSeeds
from .ik_solver import IKResult
from .ik_target import Problem, RandomSource

if TYPE_CHECKING:  # named for the checker only
    from .robot_like import RobotLike

SPECULATE = 1024
"""When no more attempts than this are running, targets run their next ones at the same time (up to this
many in all): a batch iteration costs about the same for one column as for a few hundred."""
CHUNK_TARGETS = 65536
"""Larger batches are solved in chunks of this many targets (bounded buffers: ~1.6 KiB a target)."""

log_rotation = ROTATION_PARAMETERIZATIONS["rotation_vector"].from_rotation
"""log(C) (N, 3) [rad] of rotations C (N, 3, 3): the rotation vector, θ in [0, π]."""


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
    robot: RobotLike,
    problem: Problem,
    p_d: np.ndarray,
    C_d: np.ndarray,
    q0: np.ndarray | None,
    rng: RandomSource,
) -> IKBatchResult:
    """Solve every target (p_d (N, 3), C_d (N, 3, 3)) vectorized; see the module doc."""
    kin, dof, n, c = robot.engine, robot.dof, len(p_d), CHUNK_TARGETS
    if n > c:  # q0 (N, dof) split with the targets, q0 (dof,) shared
        cut = [slice(a, a + c) for a in range(0, n, c)]
        Q0 = [q0 if q0 is None or q0.ndim == 1 else q0[k] for k in cut]
        parts = [solve_batch(robot, problem, p_d[k], C_d[k], q, rng) for k, q in zip(cut, Q0, strict=True)]
        return IKBatchResult(*(np.concatenate([getattr(x, f.name) for x in parts]) for f in fields(parts[0])))
    seeds = BatchSeeds(robot, problem, p_d, C_d, q0)
    attempts = seeds.count + problem.restarts
    rows, sqrt_w, position_rows = problem.rows, problem.sqrt_weights, problem.position_rows
    tol_p, tol_r, max_iterations = problem.tol_position, problem.tol_rotation, problem.max_iterations
    run = step.moving(kin, (problem.fid,))  # the coordinates [c0, c1) that move the frame: stepped
    cs, limits = run.coords, run.limits
    lower, upper = (bound[:, None] for bound in limits.bounds)
    q_ns, free = problem.q_ns, run.free  # the other coordinates: at the nullspace target if there is one
    if q_ns is not None:
        q_ns, pulled = q_ns[cs], problem.q_ns_within[free][:, None]  # type: ignore[index]
    # a full pose's rotation rows are weighted by ρ: |S e|² in the damping, λ² S⁻² on A's diagonal (ik_step)
    row_damping = step.POSE_ROW_DAMPING if rows is None else np.ones(len(rows))  # S⁻²
    row_weight_sq = 1.0 / row_damping  # S²
    winner = np.full(n, attempts, dtype=np.intp)  # each target's first converged attempt (none yet)
    launched = np.zeros(n, dtype=np.intp)  # attempts started so far
    log: list[tuple[np.ndarray, ...]] = []  # every finished attempt: target, attempt, iterations, ...
    # one column per running attempt, compacted as they end: (target, attempt, iterations so far) and
    # rows q (dof), |∂φ/∂q| at the last iteration (dof; -1: none yet), the scores of the last STALL_SPAN
    # iterations (oldest first), the best score and the iterations since (ik_step.gives_way), the target's
    # p_d (3) and C_d (9)
    H, B = 2 * dof, 2 * dof + step.STALL_SPAN  # history, best
    P, S = B + 2, B + 14  # p_d, C_d up to S
    meta, state = np.empty((3, 0), dtype=np.intp), np.empty((S, 0))
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
            if q_ns is not None:
                block[free] = pulled
            block[dof:H], block[B], block[B + 1] = -1.0, np.inf, 0.0
            block[P : P + 3], block[P + 3 : S] = p_d[new].T, C_d[new].reshape(-1, 9).T
            meta, state = np.concatenate((meta, new_meta), axis=1), np.concatenate((state, block), axis=1)
        r, (tid, att, it) = meta.shape[1], meta
        from_q0 = (att == 0) & problem.patient_first
        patient = (att == attempts - 1) | from_q0
        if not r:
            break
        if r > space.capacity:
            space = _Workspace(r, dof)
        q, history, pd, Cd = state[:dof], state[H:B], state[P : P + 3], state[P + 3 : S].reshape(3, 3, r)
        T, J = space.pose[..., :r], space.jac[..., :r]  # (4, 4, r), (6, dof, r): the chain writes rows
        batch.evaluate(
            kin, q.T, problem.fid, pin.LOCAL_WORLD_ALIGNED, out=(T.transpose(2, 0, 1), J.transpose(2, 0, 1))
        )
        e = np.empty((6, r))
        np.subtract(pd, T[:3, 3], out=e[:3])
        e[3:] = log_rotation(np.einsum("ikn,jkn->nij", Cd, T[:3, :3]), warn=False).T  # log(C_d Cᵀ)
        if rows is None:
            err, (ep, er) = e, np.sqrt(np.einsum("kin,kin->kn", e.reshape(2, 3, r), e.reshape(2, 3, r)))
        else:
            e_d = np.einsum("kin,jkn->jin", Cd, e.reshape(2, 3, r)).reshape(6, r)[rows]  # C_dᵀ e, blockwise
            ep = np.sqrt(np.einsum("in,in->n", e_d[position_rows], e_d[position_rows]))
            er = np.sqrt(np.einsum("in,in->n", e_d[~position_rows], e_d[~position_rows]))
            err = e_d if sqrt_w is None else e_d * sqrt_w[:, None]
        score = ep + SEED_ROTATION_WEIGHT * er
        done = (ep <= tol_p) & (er <= tol_r)
        best = score < step.STUCK_RATIO * state[B]  # a new best; the count of iterations since restarts
        state[B], state[B + 1] = np.where(best, score, state[B]), np.where(best, 0.0, state[B + 1] + 1)
        stopped = step.gives_way(it, score, history, patient, state[B + 1], from_q0)
        end = done | (it == max_iterations) | stopped
        history[:-1], history[-1] = history[1:].copy(), score  # oldest first
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
            x, J, gradient = q[cs], J[:, cs], state[dof + cs.start : dof + cs.stop]
            if limits.any:
                w, gradient[:] = limits.inverse_weights(x, gradient)
            squared = row_weight_sq @ (err * err)  # |S e|²
            diagonal = row_damping[:, None] * step.damping(squared, problem.damping_sq)
            nullspace = (q_ns, problem.gain, score)
            np.clip(step.take_steps(x, J, err, w, diagonal, nullspace, space.buffers), lower, upper, out=x)
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
    result = _resolve(log, winner, (tol_p, tol_r))
    limits.wrap(result.q[:, cs])  # the stepped coordinates' continuous joints into [-π, π)
    return result


def _resolve(log: list[tuple[np.ndarray, ...]], winner: np.ndarray, tol: tuple) -> IKBatchResult:
    """Each target's outcome from its finished attempts, as the single solver takes them one after
    another: the attempts up to the first converged one count (iterations summed), and the best score
    among them wins (the earliest on a tie)."""
    tid, att, it, score, ep, er, q = (np.concatenate(column) for column in zip(*log, strict=True))
    counted = att <= winner[tid]
    tid, att, it, score, ep, er, q = (a[counted] for a in (tid, att, it, score, ep, er, q))
    total = np.bincount(tid, weights=it, minlength=len(winner)).astype(np.intp)
    order = np.lexsort((att, score, tid))
    first = order[np.r_[True, tid[order][1:] != tid[order][:-1]]]  # best per target, targets ascending
    success = (ep[first] <= tol[0]) & (er[first] <= tol[1])
    return IKBatchResult(q[first], success, total, ep[first], er[first], att[first])


class _Workspace:
    """Buffers for up to ``capacity`` columns reused from iteration to iteration (fresh arrays of a few MiB
    cost a page fault per 4 KiB): poses, two Jacobians (compacted one into the other), and the step's
    J W⁻¹ and A (``buffers``)."""

    def __init__(self, capacity: int, dof: int) -> None:
        self.capacity, self.pose = capacity, np.empty((4, 4, capacity))
        self.jac, self.spare = np.empty((6, dof, capacity)), np.empty((6, dof, capacity))
        self.buffers = (np.empty((6, dof, capacity)), np.empty(36 * capacity))

    def compact(self, J: np.ndarray, keep: np.ndarray) -> np.ndarray:
        """J's kept columns, in the spare Jacobian buffer (which becomes the next iteration's)."""
        out = np.compress(keep, J, axis=2, out=self.spare[..., : int(keep.sum())])
        self.jac, self.spare = self.spare, self.jac
        return out


__all__ = ["IKBatchResult", "solve_batch"]
