"""The set of every IK solution of a pose (:class:`IKSolutions`), one pose's answers turned into it with
scalars (:func:`one_pose`), and the tolerances both paths share; the batch path is
:mod:`.ik_candidates`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Callable

    from .robot_like import RobotLike

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
    robot: RobotLike


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
    """:func:`.ik_candidates.candidates_to_solutions` of one pose's exact answers Q (k, n) with
    ``within_limits=True`` and ``all_turns=False``, written with scalars (a few candidates: numpy's
    per-call cost would dominate; measured, this beats one batch-chain call for all of them): a candidate
    is dropped at its first joint outside the limits (the one-turn joints come first), each survivor
    checked by the frame handle. The same formulas, order and tolerances (duplicates dropped among the
    candidates within the limits)."""
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


__all__ = [
    "ACCEPT",
    "DEGENERATE",
    "POLISH",
    "SAME",
    "TURN_TOL",
    "TWO_PI",
    "Chain",
    "IKSolutions",
    "joined",
    "one_pose",
]
