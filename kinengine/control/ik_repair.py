"""Collision-free IK: ``inverse_kinematics(..., avoid_collisions=True)`` repairs or rejects a colliding
solution, ``ik_solutions(..., avoid_collisions=True)`` drops the colliding ones."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import TYPE_CHECKING, TypeVar

import numpy as np

if TYPE_CHECKING:
    from .robot_like import RobotLike

R = TypeVar("R")
S = TypeVar("S")


def collision_free(
    robot: RobotLike, result: R, solve: Callable[[np.ndarray], R], attempts: int, rng: object
) -> R:
    """A solution in collision (``robot.in_collision``) is repaired by solving again from random
    collision-free starts (up to ``attempts`` times) and rejected (success False) if every one collides. A
    batch's colliding rows are rejected (success False), not re-solved."""
    success = result.success  # type: ignore[attr-defined]
    if isinstance(success, np.ndarray):  # IKBatchResult
        hit = np.asarray(robot.in_collision(result.q), dtype=bool)  # type: ignore[attr-defined]
        return dataclasses.replace(result, success=success & ~hit)  # type: ignore[type-var]
    if not robot.in_collision(result.q):  # type: ignore[attr-defined]
        return result
    generator = np.random.default_rng(rng if isinstance(rng, (int, np.random.Generator)) else None)
    for _ in range(max(attempts, 1)):
        q0 = robot.random_configuration(rng=generator)
        if robot.in_collision(q0):
            continue
        again = solve(q0)
        if again.success and not robot.in_collision(again.q):  # type: ignore[attr-defined]
            return again
    return dataclasses.replace(result, success=False)  # type: ignore[type-var]


def without_collisions(robot: RobotLike, solutions: S) -> S:
    """``ik_solutions(..., avoid_collisions=True)``: the solutions in collision (``robot.in_collision``)
    dropped, the others kept in their order; a batch's rows compacted and padded with NaN again."""
    q = np.asarray(solutions.q)  # type: ignore[attr-defined]
    valid = ~np.isnan(q[..., 0])
    hit = np.zeros(valid.shape, dtype=bool)
    if valid.any():
        hit[valid] = np.asarray(robot.in_collision(q[valid]), dtype=bool).reshape(-1)
    keep = valid & ~hit
    limits = np.asarray(solutions.within_limits)  # type: ignore[attr-defined]
    if q.ndim == 2:  # one pose
        count = int(keep.sum())
        return dataclasses.replace(  # type: ignore[type-var]
            solutions, q=q[keep], count=count, reachable=count > 0, within_limits=limits[keep]
        )
    order = np.argsort(~keep, axis=1, kind="stable")  # kept solutions first, in their order
    kept = np.take_along_axis(keep, order, axis=1)
    q = np.take_along_axis(q, order[..., None], axis=1)
    q[~kept] = np.nan
    limits = np.take_along_axis(limits, order, axis=1) & kept
    count = keep.sum(axis=1)
    width = int(count.max()) if len(count) else 0
    return dataclasses.replace(  # type: ignore[type-var]
        solutions, q=q[:, :width], count=count, reachable=count > 0, within_limits=limits[:, :width]
    )
