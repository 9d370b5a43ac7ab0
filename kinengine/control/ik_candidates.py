"""The post-processing of a closed-form solver's raw answers into :class:`.IKSolutions`, one pose or a
batch alike.

From raw joint angles of the n chain joints, flat over all candidates of all poses (M answers, sorted by
pose), steps 0–2 in one pass per candidate (:func:`placed`: the C chain's ``Kernel.candidates`` in
kinengine/kinematics/chainkernel.c, or its numpy twin where the extension is not built):

0. wrap into the joint ranges: continuous joints (no limits) into (−π, π]; a limited joint takes the
   2π shift inside [lower, upper] nearest the reference (``q_near``, else 0); outside every shift: not
   within the limits (dropped, or kept and flagged with ``within_limits=False``);
1. check: the frame's pose at each candidate against the target; a candidate further than ``ACCEPT``
   [m, rad] from it is dropped (the solver's least-squares answers of unreachable poses), unless it is
   polished to it first (a degenerate answer, or one of an idealized chain: damped least squares from
   it, then steps 0–2 again);
2. deduplicate: candidates of one pose closer than ``SAME`` [rad] (angles compared modulo 2π) are one;

then ``all_turns`` adds every other shift that stays inside, each pose's solutions are sorted by
distance |q − q_near| (within-limits first; a continuous joint's difference taken modulo 2π, into
(−π, π], as its angle is reported there whatever q_near's turn), and a batch is padded with NaN.

``singular``: the solver met a degenerate subproblem (its least-squares answer meets the target's
position): joint axes line up, and the solutions there form a continuum (e.g. a spherical wrist at
q5 = 0, where only q4 + q6 is fixed) or coincide (a stretched elbow). A representative set is returned:
the solver's answer, its rotation about the aligned axes completed by a few damped least-squares
iterations when it is not exact; with ``q_near``, each is then moved along the continuum toward q_near
(the null direction of the frame's Jacobian there, checked again), so that on a continuum that is a
line in joint space (a spherical wrist at q5 = 0) q_near itself is returned when it is a solution.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from ..kinematics import batch, compiler
from ..kinematics.compiler import compiled_chain
from .ik_ranges import all_turns_of, shifted_into_ranges, wrap_pi
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

LIMIT_MARGIN = 0.1
"""[rad] an idealized chain's answer up to this far outside a joint's limits is polished too: next to a
singular set the real chain's solution can lie inside them where the ideal chain's does not (xArm7,
joint2 at its limit: 0.005 rad)."""
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
    ls: np.ndarray | None,
    near: np.ndarray,
    has_near: bool,
    *,
    within_limits: bool,
    all_turns: bool,
    single: bool,
    workers: int | None = None,
) -> IKSolutions:
    """IKSolutions of poses (N, 4, 4) from the solver's raw answers, flat and sorted by pose: ``row`` (M,)
    the pose of each, ``q`` (M, n) the chain's angles [rad], ``ls`` (M,) its least-squares flags (None:
    none is);
    ``near`` (dof,) or (N, dof) the reference q (its other coordinates fill the result); ``workers``: the
    forward kinematics' threads. One pose (``single``) and a batch take the same steps."""
    robot, columns, frame = chain.robot, chain.columns, chain.frame
    n_poses, dof = len(poses), chain.dof
    base = near if near.ndim == 2 else near[None]
    shifts = all_turns and len(chain.many_turns) > 0
    # 0.-2. into the joint ranges, checked against the targets, deduplicated
    repair = ls is not None or chain.approximate
    out, turns = placed(chain, poses, row, q, base, has_near, within_limits, shifts, workers, not repair)
    e = dof + len(columns)  # out's columns: full q, the chain's wrapped angles, kept, inside, errors
    singular = None
    if repair:  # degenerate answers repaired, an idealized chain's polished
        ls = np.zeros(len(row), dtype=bool) if ls is None else ls
        err_p, err_r = out[:, e + 2], out[:, e + 3]
        exact = (err_p <= ACCEPT) & (err_r <= ACCEPT)
        degenerate = ls & (err_p <= DEGENERATE)
        singular = np.zeros(n_poses, dtype=bool)
        singular[row[degenerate]] = True
        polish = (err_p <= POLISH) & (err_r <= POLISH) if chain.approximate else degenerate
        fix = np.flatnonzero((degenerate | polish) & ~exact)
        angles = shifted_into_ranges(chain, out[fix, dof:e], None, False)[0]  # the 2π shifts into the limits
        if within_limits:  # what cannot be a solution within the limits is not polished (a degenerate is)
            outside = np.maximum(chain.lower - angles, angles - chain.upper).max(axis=1, initial=0.0)
            near = outside <= (LIMIT_MARGIN if chain.approximate else 0.0)
            chosen = (out[fix, e + 1] != 0) | ls[fix] | near
            fix, angles = fix[chosen], angles[chosen]
        if len(fix):  # from the angles shifted into the limits (the iterations stay within them)
            start = out[fix, :dof]
            start[:, columns] = angles
            repaired = _repaired(robot, frame, start, poses[row[fix]])
            q = out[:, dof:e].copy()
            q[fix] = repaired[:, columns]
            if chain.approximate:  # the ideal chain's least-squares answers: two real branches about to merge
                row, q = _with_mirrors(chain, poses, row, q, out[:, dof:e], fix[ls[fix]], start[ls[fix]])
            out, turns = placed(chain, poses, row, q, base, has_near, within_limits, shifts, workers)
    keep = out[:, e].nonzero()[0]
    full = out[keep, :dof]
    inside = np.ones(len(keep), dtype=bool) if within_limits else out[keep, e + 1] != 0
    if has_near and singular is not None and singular.any():  # a continuum: its member nearest q_near
        full = _toward_near(chain, poses, row[keep], full, base, singular)
    if single and turns is None:  # one pose: its rows need no pose index
        if has_near and len(full) > 1:
            order = np.lexsort((near_distance(chain, full, base[0]), ~inside))
            full, inside = full[order], inside[order]
        elif not within_limits and len(full) > 1:
            order = np.argsort(~inside, kind="stable")
            full, inside = full[order], inside[order]
        c = len(full)
        return IKSolutions(
            full, c, c > 0, singular is not None and bool(singular[0]), inside, frame, chain.joints
        )
    row = row[keep]
    if turns is not None:
        row, inside, full = all_turns_of(chain, row, inside, full, *(k[keep] for k in turns))
    # 3. within the limits first, then by distance to q_near, within each pose; padded with NaN
    if has_near and len(row) > 1:
        distance = near_distance(chain, full, base[0 if len(base) == 1 else row])
        order = np.lexsort((distance, ~inside, row))
        row, full, inside = row[order], full[order], inside[order]
    elif not within_limits and len(row) > 1:
        order = np.lexsort((~inside, row))
        row, full, inside = row[order], full[order], inside[order]
    singular = np.zeros(n_poses, dtype=bool) if singular is None else singular
    if single:
        c = len(row)
        return IKSolutions(full, c, c > 0, bool(singular[0]), inside, frame, chain.joints)
    count = np.bincount(row, minlength=n_poses)
    K = int(count.max(initial=0))
    out = np.full((n_poses, K, dof), np.nan)
    limits = np.zeros((n_poses, K), dtype=bool)
    slot = np.arange(len(row)) - np.searchsorted(row, row)
    out[row, slot] = full
    limits[row, slot] = inside
    return IKSolutions(out, count, count > 0, singular, limits, frame, chain.joints)


def near_distance(chain: Chain, full: np.ndarray, near: np.ndarray) -> np.ndarray:
    """|q − q_near| of each row of ``full`` (M, dof) to ``near`` ((dof,) or (M, dof)), a continuous joint's
    difference wrapped into (−π, π] (every turn of it is the same configuration)."""
    d = full - near
    continuous = chain.columns[chain.continuous]
    if len(continuous):
        d[:, continuous] = wrap_pi(d[:, continuous])
    return np.linalg.norm(d, axis=1)


def placed(
    chain: Chain,
    poses: np.ndarray,
    row: np.ndarray,
    q: np.ndarray,
    base: np.ndarray,
    has_near: bool,
    within_limits: bool,
    shifts: bool,
    workers: int | None = None,
    skip: bool = False,
) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray] | None]:
    """Steps 0-2 for raw angles q (M, n) of poses[row] (rows sorted): out (M, dof + n + 4) = (each
    candidate's q within the ranges (base's (1 or N, dof) other coordinates), its chain angles wrapped into
    (−π, π], kept, inside, position [m] and rotation [rad] errors), kept: exact, within the limits unless
    not ``within_limits``, and no earlier kept candidate of its pose the same to SAME modulo 2π (flags 1.0
    or 0.0); with ``shifts`` the 2π shifts (k_min, k_max, k_best) (M, n) each; with ``skip`` and
    ``within_limits`` a candidate outside the limits is not checked (its errors inf). The C kernel
    (kinengine/kinematics/chainkernel.c, ``Kernel.candidates``) when built, else its numpy twin below."""
    (M, n), dof = q.shape, chain.dof
    out = np.empty((M, dof + n + 4))
    kernel = chain.kernel
    if kernel is not None:
        k = np.empty((M, n, 3)) if shifts else None
        kernel.candidates(
            q,
            None if len(poses) == 1 else row,
            poses,
            base,
            chain.table,
            out,
            k,
            has_near,
            within_limits,
            skip,
            ACCEPT,
            SAME,
            TURN_TOL,
        )
        return out, None if k is None else (k[:, :, 0], k[:, :, 1], k[:, :, 2])
    wrapped = wrap_pi(q)
    whole = base[row if len(base) > 1 else np.zeros_like(row)]
    angles, inside, turns = shifted_into_ranges(
        chain, wrapped, whole[:, chain.columns] if has_near else None, shifts
    )
    full, e = out[:, :dof], dof + n
    full[:] = whole
    full[:, chain.columns] = angles
    err_p, err_r = np.full(len(q), np.inf), np.full(len(q), np.inf)
    checked = np.flatnonzero(inside) if skip and within_limits else slice(None)
    err_p[checked], err_r[checked] = residuals(
        chain.robot, chain.frame, full[checked], poses, row[checked], workers
    )
    keep = (err_p <= ACCEPT) & (err_r <= ACCEPT)
    if within_limits:
        keep &= inside
    kept = np.flatnonzero(keep)
    keep[kept[_duplicates(row[kept], wrapped[kept])]] = False
    out[:, dof:e], out[:, e], out[:, e + 1], out[:, e + 2], out[:, e + 3] = (
        wrapped,
        keep,
        inside,
        err_p,
        err_r,
    )
    return out, turns


def _duplicates(row: np.ndarray, wrapped: np.ndarray) -> np.ndarray:
    """(M,) True for a candidate equal to an earlier one of its pose (rows sorted) to SAME modulo 2π."""
    rank = np.arange(len(row)) - np.searchsorted(row, row)
    duplicate = np.zeros(len(row), dtype=bool)
    for back in range(1, int(rank.max(initial=0)) + 1):
        later = np.flatnonzero(rank >= back)
        d = np.abs(wrapped[later] - wrapped[later - back])  # both in (−π, π]: |d| < 2π
        duplicate[later[(np.minimum(d, TWO_PI - d) <= SAME).all(axis=1)]] = True
    return duplicate


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


def _with_mirrors(
    chain: Chain,
    poses: np.ndarray,
    row: np.ndarray,
    q: np.ndarray,
    ideal: np.ndarray,
    fold: np.ndarray,
    start: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Near a fold of the real chain its two solutions q± ≈ q_f ± δ lie on either side of the ideal chain's
    least-squares answer q_f (wrapped angles ``ideal`` of candidates ``fold``), of which the polish found
    one (q): the other is polished from its mirror 2 q_f − q and added to the candidates (rows sorted).
    ``start`` (len(fold), dof): the polish's start rows of those candidates (their other coordinates)."""
    if not len(fold):
        return row, q
    d = wrap_pi(q[fold] - ideal[fold])
    begin = start.copy()  # the polish's start rows of the fold candidates (their other coordinates)
    begin[:, chain.columns] = shifted_into_ranges(chain, wrap_pi(ideal[fold] - d), None, False)[0]
    mirrored = _repaired(chain.robot, chain.frame, begin, poses[row[fold]])[:, chain.columns]
    order = np.argsort(np.concatenate((row, row[fold])), kind="stable")
    return np.concatenate((row, row[fold]))[order], np.concatenate((q, mirrored))[order]


def _toward_near(
    chain: Chain, poses: np.ndarray, row: np.ndarray, full: np.ndarray, base: np.ndarray, singular: np.ndarray
) -> np.ndarray:
    """``full`` (K, dof) with each solution of a singular pose moved toward its reference q (``base`` (1, dof)
    or (N, dof)) along the continuum: Δ = n·nᵀ(q_near − q) with n the null direction of the frame's
    Jacobian over the chain's joints; kept where it reproduces the pose (``ACCEPT``), stays within the
    limits and is nearer q_near. Exact where the continuum is a line in joint space (two aligned axes
    turning against each other, as a spherical wrist at q5 = 0); elsewhere the representative stays."""
    robot, frame, columns = chain.robot, chain.frame, chain.columns
    out = full.copy()
    for k in np.flatnonzero(singular[row]):
        q = full[k]
        near = base[0 if len(base) == 1 else row[k]]
        J = robot.jacobian(q, frame, "world")[:, columns]
        n = np.linalg.svd(J)[2][-1]
        start = q.copy()
        start[columns] += n * (n @ (near[columns] - q[columns]))
        moved = start[None]
        err_p, err_r = residuals(robot, frame, moved, poses[row[k]][None])
        angles = moved[0, columns]
        if (
            err_p[0] <= ACCEPT
            and err_r[0] <= ACCEPT
            and (angles >= chain.lower).all()
            and (angles <= chain.upper).all()
            and np.linalg.norm(moved[0] - near) < np.linalg.norm(q - near)
        ):
            out[k] = moved[0]
    return out


def _repaired(robot: RobotLike, frame: str, q: np.ndarray, T_d: np.ndarray) -> np.ndarray:
    """Degenerate answers (the position met, the rotation about a line of aligned joint axes not) and
    an idealized chain's answers: a few damped least-squares iterations from each."""
    result = robot.inverse_kinematics(
        T_d, frame, q, tol_position=ACCEPT / 1000, tol_rotation=ACCEPT / 1000, restarts=0, method="numeric"
    )
    return np.asarray(result.q)


__all__ = ["FEW", "POSES_PER_WORKER", "candidates_to_solutions", "residuals", "shared_by_poses"]
