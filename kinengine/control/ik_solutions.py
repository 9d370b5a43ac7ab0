"""The set of every IK solution of a pose (:class:`IKSolutions`) and the tolerances of the
post-processing that builds it (:mod:`.ik_candidates`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    from ..kinematics.chainkernel import Kernel
    from .robot_like import RobotLike

ACCEPT = 1e-9
"""[m and rad] a candidate whose frame pose is further than this from the target is no solution."""
SAME = 1e-7
"""[rad] candidates of one pose whose angles all agree to this (modulo 2π) are one solution."""
POLISH = 1e-2
"""[m and rad] an answer of an idealized chain (rounded axes) this close to the target is polished."""
DEGENERATE = 1e-6
"""[m] a least-squares answer this close to the target's position met a degenerate subproblem (a line of
aligned joint axes: the pose is singular), not an unreachable pose; its rotation is repaired numerically."""
TWO_PI = 2.0 * np.pi
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
    table: np.ndarray  # (n, 4) per joint: column, kind (CONTINUOUS, ONE_TURN, MANY_TURNS), lower, upper
    kernel: Kernel | None  # the frame's C chain (kinengine/kinematics/chainkernel.c), None if not built
    robot: RobotLike
    dof: int  # the robot's


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
]
