"""``inverse_kinematics(..., avoid_collisions=True)``: keep or repair only collision-free IK solutions."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import TYPE_CHECKING, TypeVar

import numpy as np

if TYPE_CHECKING:
    from .robot_like import RobotLike

R = TypeVar("R")


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
