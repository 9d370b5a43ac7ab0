"""The set of every IK solution of a pose, and the vectorized post-processing of a solver's raw answers.

From raw joint angles (N, K, n) of the n chain joints to :class:`IKSolutions`, every step a numpy pass
over all candidates of all poses at once (flat (M,) arrays, M = number of raw answers):

1. check: the frame's pose at each candidate (the batch chain) against the target; a candidate further
   than ``ACCEPT`` [m, rad] from it is dropped (the solver's least-squares answers of unreachable poses),
   unless it is polished to it first (a degenerate answer, or one of an idealized chain: damped least
   squares from it);
2. deduplicate: candidates of one pose closer than ``SAME`` [rad] (angles compared modulo 2π) are one;
3. wrap into the joint ranges: continuous joints (no limits) into (−π, π]; a limited joint takes the
   2π shift inside [lower, upper] nearest the reference (``q_near``, else 0); ``all_turns`` adds every
   other shift that stays inside; outside every shift: dropped, or kept and flagged (``within_limits=False``);
4. sort each pose's solutions by distance |q − q_near| (within-limits first), and pad with NaN.

``singular``: the solver met a degenerate subproblem (its least-squares answer meets the target's
position): joint axes line up, and the solutions there form a continuum (e.g. a spherical wrist at
q5 = 0, where only q4 + q6 is fixed) or coincide (a stretched elbow). A representative set is returned:
the solver's answer, its rotation about the aligned axes completed by a few damped least-squares
iterations when it is not exact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ..kinematics import batch, compiler
from ..kinematics.compiler import compiled_chain

if TYPE_CHECKING:
    from collections.abc import Callable

    from ..robot import Robot

ACCEPT = 1e-9
"""[m and rad] a candidate whose frame pose is further than this from the target is no solution."""
SAME = 1e-7
"""[rad] candidates of one pose whose angles all agree to this (modulo 2π) are one solution."""
POLISH = 1e-3
"""[m and rad] an answer of an idealized chain (rounded axes) this close to the target is polished."""
DEGENERATE = 1e-6
"""[m] a least-squares answer this close to the target's position met a degenerate subproblem (a line of
aligned joint axes: the pose is singular), not an unreachable pose; its rotation is repaired numerically."""
TWO_PI = 2.0 * np.pi
ROTATION = ACCEPT * math.sqrt(2)
"""|C − C_d|_F at a rotation error of ACCEPT (to first order): one_pose's scalar form of the test."""
CONTINUOUS, ONE_TURN, MANY_TURNS = 0, 1, 2
"""Kinds of joint range: none; within (−π, π] (one 2π shift fits: 0); reaching beyond it."""
TURN_TOL = TWO_PI * 1e-12
"""[rad] a limit exceeded by at most this is met (the angle is put on it)."""
FEW = 64
"""Up to this many candidates are checked by the C batch chain in the calling thread (no thread hand-over)."""


class Chain(Protocol):
    """What the post-processing needs of a closed-form solver (:class:`.closed_form.ClosedFormChain`)."""

    frame: str
    joints: tuple[str, ...]  # the chain's joint names, base to tip
    columns: np.ndarray  # their indices into q
    lower: np.ndarray  # their limits [rad]
    upper: np.ndarray
    continuous: np.ndarray  # True: no limits
    one_turn: np.ndarray  # indices of the limited joints whose range lies within (−π, π]: one shift (0)
    many_turns: np.ndarray  # indices of the other limited joints
    approximate: bool  # True: the solver solves an idealized chain; its answers are polished
    scalar_joints: list[tuple[int, int, int, float, float]]  # (index, column, kind, lower, upper) per joint
    pose: Callable[[np.ndarray], np.ndarray]  # T_IF of a q (dof,), unchecked
    whole: bool  # the chain's joints are all of q's coordinates, in order
    robot: Robot


@dataclass(frozen=True)
class IKSolutions:
    """Every distinct joint solution of a pose T_IF (or of each pose of a batch).

    One pose (4, 4): ``q`` (k, dof) [rad], ``count`` int, ``reachable`` bool, ``singular`` bool,
    ``within_limits`` (k,) bool. A batch (N, 4, 4): ``q`` (N, K, dof) padded with NaN, ``count`` (N,),
    ``reachable`` (N,), ``singular`` (N,), ``within_limits`` (N, K) (False in the padding).
    ``reachable``: at least one solution is returned. ``singular``: the solutions form a continuum (two
    joint axes on one line, or a degenerate subproblem) of which a representative set is returned.
    ``joints``: the names of the coordinates solved for; the others (which do not move ``frame``) hold
    q_near's values, or zero clipped into the limits.
    """

    q: np.ndarray
    count: int | np.ndarray
    reachable: bool | np.ndarray
    singular: bool | np.ndarray
    within_limits: np.ndarray
    frame: str
    joints: tuple[str, ...]

    def __len__(self) -> int:
        return len(self.q)

    def __str__(self) -> str:
        if np.ndim(self.count) == 0:
            flag = ", singular (a representative set of a continuum)" if self.singular else ""
            return f"{self.count} IK solutions of frame {self.frame!r}{flag}"
        count = np.asarray(self.count)
        return (
            f"IK solutions of frame {self.frame!r} for {len(count)} poses: {int(count.sum())} in all, "
            f"{int(np.count_nonzero(count))} poses reachable, {int(np.count_nonzero(self.singular))} singular"
        )


def candidates_to_solutions(
    chain: Chain,
    poses: np.ndarray,
    row: np.ndarray,
    q: np.ndarray,
    ls: np.ndarray,
    near: np.ndarray,
    has_near: bool,
    *,
    within_limits: bool,
    all_turns: bool,
    single: bool,
    workers: int | None = None,
) -> IKSolutions:
    """IKSolutions of poses (N, 4, 4) from the solver's raw answers, flat and sorted by pose: ``row`` (M,)
    the pose of each, ``q`` (M, n) the chain's angles [rad], ``ls`` (M,) its least-squares flags;
    ``near`` (dof,) or (N, dof) the reference q (its other coordinates fill the result); ``workers``: the
    forward kinematics' threads."""
    robot, columns, frame = chain.robot, chain.columns, chain.frame
    n_poses, dof = len(poses), robot.dof
    wrapped = _wrap_pi(q)
    ref = None
    if has_near:  # (M, n) the reference's angles of each candidate's pose
        ref = (
            near[row][:, columns]
            if near.ndim == 2
            else np.broadcast_to(near[columns], (len(row), len(columns)))
        )
    # 0. into the joint ranges first (the shift nearest the reference); what cannot be a solution within
    # the limits is not checked (a least-squares answer is: it may be repaired into them)
    angles, inside, turns = _turns(chain, wrapped, ref, all_turns)
    if within_limits:
        keep = np.flatnonzero(inside | ls)
        row, wrapped, angles, inside, ls = row[keep], wrapped[keep], angles[keep], inside[keep], ls[keep]
        ref = None if ref is None else ref[keep]
        turns = None if turns is None else (turns[0][keep], turns[1][keep], turns[2][keep])
    if chain.whole:  # the chain's joints are q's coordinates, in order
        full = angles
    else:
        full = near[row] if near.ndim == 2 else np.repeat(near[None], len(row), axis=0)
        full[:, columns] = angles
    # 1. the frame's pose at every candidate against its target; degenerate answers repaired, an
    # idealized chain's polished
    err_p, err_r = residuals(robot, frame, full, poses, row, workers)
    exact = (err_p <= ACCEPT) & (err_r <= ACCEPT)
    singular = np.zeros(n_poses, dtype=bool)
    fix = np.zeros(0, dtype=np.intp)
    if ls.any() or chain.approximate:
        degenerate = ls & (err_p <= DEGENERATE)
        singular[row[degenerate]] = True
        polish = (err_p <= POLISH) & (err_r <= POLISH) if chain.approximate else degenerate
        fix = np.flatnonzero((degenerate | polish) & ~exact)
    if len(fix):  # from the angles shifted into the limits (the iterations stay within them)
        start = full[fix]
        start[:, columns] = _turns(chain, wrapped[fix], None, False)[0]
        repaired = _repaired(robot, frame, start, poses[row[fix]])
        err_p, err_r = residuals(robot, frame, repaired, poses, row[fix])
        exact[fix] = (err_p <= ACCEPT) & (err_r <= ACCEPT)
        wrapped[fix] = _wrap_pi(repaired[:, columns])
        fixed = _turns(chain, wrapped[fix], None if ref is None else ref[fix], all_turns)
        angles[fix], inside[fix] = fixed[0], fixed[1]
        if turns is not None and fixed[2] is not None:
            for k, k_fix in zip(turns, fixed[2], strict=True):
                k[fix] = k_fix
        if not chain.whole:
            full[np.ix_(fix, columns)] = fixed[0]
    # 2. duplicates (modulo 2π) among the exact candidates of a pose; 3. the limit filter: one selection
    e = np.flatnonzero(exact)
    keep = e[~_duplicates(row[e], wrapped[e])]
    if within_limits:
        keep = keep[inside[keep]]
    row, full, inside = row[keep], full[keep], inside[keep]
    if all_turns and turns is not None:
        row, inside, full = _all_turns(chain, row, inside, full, *(k[keep] for k in turns))
    # 4. within the limits first, then by distance to q_near, within each pose; padded with NaN
    if has_near:
        distance = np.linalg.norm(full - (near[row] if near.ndim == 2 else near), axis=1)
        order = np.lexsort((distance, ~inside, row))
        row, full, inside = row[order], full[order], inside[order]
    elif not within_limits:
        order = np.lexsort((~inside, row))
        row, full, inside = row[order], full[order], inside[order]
    count = np.bincount(row, minlength=n_poses)
    if single:
        c = int(count[0])
        return IKSolutions(full, c, c > 0, bool(singular[0]), inside, frame, chain.joints)
    K = int(count.max(initial=0))
    out = np.full((n_poses, K, dof), np.nan)
    limits = np.zeros((n_poses, K), dtype=bool)
    slot = np.arange(len(row)) - np.searchsorted(row, row)
    out[row, slot] = full
    limits[row, slot] = inside
    return IKSolutions(out, count, count > 0, singular, limits, frame, chain.joints)


def joined(parts: list[IKSolutions]) -> IKSolutions:
    """One batch's IKSolutions from those of consecutive chunks of its poses (padded to the widest)."""
    K = max(p.q.shape[1] for p in parts)
    pad = [((0, 0), (0, K - p.q.shape[1]), (0, 0)) for p in parts]
    q = np.concatenate([np.pad(p.q, w, constant_values=np.nan) for p, w in zip(parts, pad, strict=True)])
    limits = np.concatenate([np.pad(p.within_limits, w[:2]) for p, w in zip(parts, pad, strict=True)])
    count = np.concatenate([p.count for p in parts])
    singular = np.concatenate([p.singular for p in parts])
    return IKSolutions(q, count, count > 0, singular, limits, parts[0].frame, parts[0].joints)


def one_pose(chain: Chain, T_d: np.ndarray, Q: np.ndarray, near: np.ndarray, has_near: bool) -> IKSolutions:
    """:func:`candidates_to_solutions` of one pose's exact answers Q (k, n) with ``within_limits=True``
    and ``all_turns=False``, written with scalars (a few candidates: numpy's per-call cost would dominate;
    measured, this beats one batch-chain call for all of them): a candidate is dropped at its first joint
    outside the limits (the one-turn joints come first), each survivor checked by the frame handle. The
    same formulas, order and tolerances (duplicates dropped among the candidates within the limits)."""
    base = near.tolist()
    refs = near[chain.columns].tolist() if has_near else None
    pose, target = chain.pose, T_d[:3].ravel().tolist()  # the frame handle: one pose, no checks
    seen: list[list[float]] = []
    rows: list[list[float]] = []
    for wrapped in Q.tolist():
        q = base.copy()
        for j, column, kind, low, high in chain.scalar_joints:
            a = wrapped[j]
            if not -math.pi < a <= math.pi:  # into (−π, π] (the solver's are in [−π, π])
                a = wrapped[j] = math.pi - (math.pi - a) % TWO_PI
            if kind == CONTINUOUS or (low <= a <= high and (refs is None or abs(refs[j] - a) <= math.pi)):
                pass  # k = 0 is the shift to take
            elif kind == ONE_TURN:  # the range lies within (−π, π]: k = 0, a limit met to TURN_TOL
                if not low - TURN_TOL <= a <= high + TURN_TOL:
                    break
                a = min(max(a, low), high)
            else:  # the 2π shift within the limits nearest the reference (else 0)
                k_min = math.ceil((low - a) / TWO_PI - 1e-12)
                k_max = math.floor((high - a) / TWO_PI + 1e-12)
                if k_min > k_max:
                    break
                k = min(max(round(((refs[j] if refs is not None else 0.0) - a) / TWO_PI), k_min), k_max)
                a = min(max(a + TWO_PI * k, low), high)
            q[column] = a
        else:
            for w in seen:
                if _same(wrapped, w):
                    break
            else:
                seen.append(wrapped)
                d = [x - y for x, y in zip(pose(np.array(q))[:3].ravel().tolist(), target, strict=True)]
                if (
                    math.hypot(d[3], d[7], d[11]) <= ACCEPT
                    and math.hypot(*d[0:3], *d[4:7], *d[8:11]) <= ROTATION
                ):
                    rows.append(q)
    full = np.array(rows, dtype=np.float64).reshape(len(rows), len(base))
    if has_near and len(full) > 1:
        full = full[np.argsort(np.linalg.norm(full - near, axis=1), kind="stable")]
    c = len(full)
    return IKSolutions(full, c, c > 0, False, np.ones(c, dtype=bool), chain.frame, chain.joints)


def _same(a: list[float], b: list[float]) -> bool:
    """Two lists of angles in (−π, π] equal to SAME modulo 2π."""
    for x, y in zip(a, b, strict=True):
        d = abs(x - y)
        if d > SAME and TWO_PI - d > SAME:
            return False
    return True


def _duplicates(row: np.ndarray, wrapped: np.ndarray) -> np.ndarray:
    """(M,) True for a candidate equal to an earlier one of its pose (rows sorted) to SAME modulo 2π."""
    rank = np.arange(len(row)) - np.searchsorted(row, row)
    duplicate = np.zeros(len(row), dtype=bool)
    for back in range(1, int(rank.max(initial=0)) + 1):
        later = np.flatnonzero(rank >= back)
        d = np.abs(wrapped[later] - wrapped[later - back])  # both in (−π, π]: |d| < 2π
        duplicate[later[(np.minimum(d, TWO_PI - d) <= SAME).all(axis=1)]] = True
    return duplicate


def _wrap_pi(a: np.ndarray) -> np.ndarray:
    """Angles into (−π, π] (the solver's are in [−π, π] already: then only −π moves)."""
    if len(a) and np.abs(a).max() <= np.pi:
        return np.where(a == -np.pi, np.pi, a)
    return np.pi - np.mod(np.pi - a, TWO_PI)


def _turns(
    chain: Chain, wrapped: np.ndarray, ref: np.ndarray | None, shifts: bool
) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray] | None]:
    """Angles (M, n) in (−π, π] shifted by 2π·k into the joint ranges: k nearest (ref − angle)/2π (ref None:
    0) among k_min..k_max (the shifts inside [lower, upper], a limit met to TURN_TOL: on it); continuous
    joints unshifted; a joint no shift puts inside keeps the shift nearest ref. A range within (−π, π]
    (``chain.one_turn``) has only k = 0. Returns (angles, inside (M,), and with ``shifts`` (k_min, k_max,
    k_best) (M, n), 0 for continuous and one-turn joints)."""
    angles = wrapped.copy()
    inside = np.ones(len(wrapped), dtype=bool)
    one, many = chain.one_turn, chain.many_turns
    if len(one):
        w, lo, hi = wrapped[:, one], chain.lower[one], chain.upper[one]
        fits = (w >= lo - TURN_TOL) & (w <= hi + TURN_TOL)
        inside &= fits.all(axis=1)
        on = np.minimum(np.maximum(w, lo), hi)
        if ref is not None:  # no shift fits: the one nearest the reference
            w = w + TWO_PI * np.rint((ref[:, one] - w) / TWO_PI)
        angles[:, one] = np.where(fits, on, w)
    k = None
    if len(many):
        w, lo, hi = wrapped[:, many], chain.lower[many], chain.upper[many]
        k_min = np.ceil((lo - w) / TWO_PI - 1e-12)
        k_max = np.floor((hi - w) / TWO_PI + 1e-12)
        k_near = np.zeros_like(w) if ref is None else np.rint((ref[:, many] - w) / TWO_PI)
        fits = k_min <= k_max
        inside &= fits.all(axis=1)
        k_best = np.where(fits, np.minimum(np.maximum(k_near, k_min), k_max), k_near)
        a = w + TWO_PI * k_best
        angles[:, many] = np.where(fits, np.minimum(np.maximum(a, lo), hi), a)
        k = (k_min, k_max, k_best)
    if not shifts:
        return angles, inside, None
    full = tuple(np.zeros_like(wrapped) for _ in range(3))
    if k is not None:
        for f, part in zip(full, k, strict=True):
            f[:, many] = part
    return angles, inside, full  # type: ignore[return-value]


def _all_turns(
    chain: Chain,
    row: np.ndarray,
    inside: np.ndarray,
    full: np.ndarray,
    k_min: np.ndarray,
    k_max: np.ndarray,
    k_best: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every 2π shift of each within-limits solution's joints whose range holds several (``many_turns``)
    that stays within the limits (the chosen one first), joint by joint: each solution repeated once per
    shift of that joint."""
    for j in chain.many_turns:
        shifts = np.where(inside, np.maximum(k_max[:, j] - k_min[:, j] + 1, 1), 1).astype(np.intp)
        source = np.repeat(np.arange(len(row)), shifts)
        step = np.arange(len(source)) - np.repeat(np.cumsum(shifts) - shifts, shifts)
        k = np.where(inside[source], k_min[source, j] + step, k_best[source, j])
        chosen = k == k_best[source, j]
        order = np.lexsort((~chosen, source))  # the chosen shift first within each solution
        source, k = source[order], k[order]
        row, inside, full = row[source], inside[source], full[source]
        k_min, k_max, k_best = k_min[source], k_max[source], k_best[source]
        full[:, chain.columns[j]] += TWO_PI * (k - k_best[:, j])
    return row, inside, full


def residuals(
    robot: Robot,
    frame: str,
    q: np.ndarray,
    poses: np.ndarray,
    row: np.ndarray | None = None,
    workers: int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Position [m] and rotation [rad, to first order: |C − C_d|_F / √2] errors of frame at q (M, dof)
    against poses[row] (M, 4, 4) (row None: poses itself); the batch chain on up to ``workers`` threads."""
    kin = robot.engine
    fid = kin.frame_id(frame)
    T = np.empty((len(q), 4, 4))
    kernel = compiled_chain(kin, fid).kernel if len(q) <= FEW or workers == 1 else None
    if kernel is not None and compiler.KERNEL is not None:  # the C chain, in this thread
        kernel.run(np.ascontiguousarray(q, dtype=np.float64), T, None, 0)
    else:
        batch.evaluate(
            kin,
            np.ascontiguousarray(q),
            kin.frame_id(frame),
            None,
            jacobian=False,
            out=(T, None),
            workers=workers,
        )
    D = T[:, :3, :] - (poses[:, :3, :] if row is None else poses[row, :3, :])
    D *= D
    errors = np.sqrt(D.reshape(len(D), 12) @ _SPLIT)  # (M, 2): one product sums both parts
    return errors[:, 0], errors[:, 1]


_SPLIT = np.zeros((12, 2))
_SPLIT[3::4, 0] = 1.0  # the position entries of a row-major 3 × 4 block
_SPLIT[[0, 1, 2, 4, 5, 6, 8, 9, 10], 1] = 0.5  # the rotation entries, halved: |C − C_d|_F² / 2


def _repaired(robot: Robot, frame: str, q: np.ndarray, T_d: np.ndarray) -> np.ndarray:
    """Degenerate answers (the position met, the rotation about a line of aligned joint axes not) and
    an idealized chain's answers: a few damped least-squares iterations from each."""
    result = robot.inverse_kinematics(
        T_d, frame, q, tol_position=ACCEPT / 10, tol_rotation=ACCEPT / 10, restarts=0, method="numeric"
    )
    return np.asarray(result.q)


__all__ = ["ACCEPT", "DEGENERATE", "SAME", "IKSolutions", "candidates_to_solutions", "joined", "residuals"]
