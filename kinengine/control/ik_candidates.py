"""The vectorized post-processing of a closed-form solver's raw answers into :class:`.IKSolutions`.

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

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from ..kinematics import batch, compiler
from ..kinematics.compiler import compiled_chain
from .ik_solutions import (
    ACCEPT,
    DEGENERATE,
    POLISH,
    SAME,
    TURN_TOL,
    TWO_PI,
    Chain,
    IKSolutions,
    joined,
)

if TYPE_CHECKING:
    from .robot_like import RobotLike

POSES_PER_WORKER = 1000
"""A batch's post-processing is shared among threads only when each gets at least this many poses."""
FEW = 64
"""Up to this many candidates are checked by the C batch chain in the calling thread (no thread hand-over)."""


def shared_by_poses(
    n: int, row: np.ndarray, post: Callable[[int, int, int, int, int | None], IKSolutions]
) -> IKSolutions:
    """``post(c0, c1, i0, i1, workers)``: the IKSolutions of poses c0..c1 of n from their candidates i0..i1
    (``row`` (M,) each candidate's pose, sorted), in shares of the poses on the batch pool's threads
    (numpy releases the GIL in its loops; each share's forward kinematics in its own thread), joined."""
    shares = max(1, min(batch.WORKERS, n // POSES_PER_WORKER))
    if shares == 1:
        return post(0, n, 0, len(row), None)
    cuts = [n * i // shares for i in range(shares + 1)]
    ends = np.searchsorted(row, cuts).tolist()
    parts: list[IKSolutions | None] = [None] * shares

    def work(i: int, _: int) -> None:
        parts[i] = post(cuts[i], cuts[i + 1], ends[i], ends[i + 1], 1)

    batch.in_shares([(i, i + 1) for i in range(shares)], work, shares)
    return joined([p for p in parts if p is not None])


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
    robot: RobotLike,
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


def _repaired(robot: RobotLike, frame: str, q: np.ndarray, T_d: np.ndarray) -> np.ndarray:
    """Degenerate answers (the position met, the rotation about a line of aligned joint axes not) and
    an idealized chain's answers: a few damped least-squares iterations from each."""
    result = robot.inverse_kinematics(
        T_d, frame, q, tol_position=ACCEPT / 10, tol_rotation=ACCEPT / 10, restarts=0, method="numeric"
    )
    return np.asarray(result.q)


__all__ = ["FEW", "POSES_PER_WORKER", "candidates_to_solutions", "residuals", "shared_by_poses"]
