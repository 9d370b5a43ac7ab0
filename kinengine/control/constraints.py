"""Inequality constraints of the differential-IK QP (:class:`kinengine.DifferentialIK` ``constraints=``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from ..errors import OptionError

FloatArray = npt.NDArray[np.float64]


class InequalityConstraint(Protocol):
    """``inequality(robot, q, dt)`` returns (G (m, dof), h (m,)) with G q̇ ≤ h at q for a step of dt [s]
    (e.g. :class:`kinengine.CollisionAvoidance`)."""

    def inequality(self, robot: Any, q: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]: ...


def checked_constraints(constraints: Sequence[InequalityConstraint]) -> tuple[InequalityConstraint, ...]:
    """The constraints as a tuple; OptionError for an object without an ``inequality`` method."""
    for constraint in constraints:
        if not callable(getattr(constraint, "inequality", None)):
            raise OptionError(f"constraints have an inequality(robot, q, dt) method, got {constraint!r}")
    return tuple(constraints)


def step_inequalities(
    constraints: Sequence[InequalityConstraint], robot: object, q: FloatArray, dt: float, dof: int
) -> tuple[FloatArray | None, FloatArray | None]:
    """The constraints' rows as G Δq ≤ h for the step Δq = q̇ dt ((None, None) without rows)."""
    if not constraints:
        return None, None
    rows = [c.inequality(robot, q, dt) for c in constraints]
    G = np.vstack([np.reshape(g, (-1, dof)) for g, _ in rows])
    if not len(G):
        return None, None
    return G, np.concatenate([np.reshape(h, -1) for _, h in rows]) * dt


__all__ = ["InequalityConstraint", "checked_constraints", "step_inequalities"]
