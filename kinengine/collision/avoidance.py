"""Keeping clear of collisions in differential IK: a linear inequality on the joint velocities per close pair.

For each checked shape pair whose signed distance d is below ``influence_distance``, the distance after one
step of ``dt`` [s], linearised, stays at or above ``min_distance``:

    d + ∇d · q̇ dt ≥ d_min,   i.e.   −∇d · q̇ ≤ gain · (d − d_min) / dt

with ∇d = ∂d/∂q from the witness points and the point Jacobians (:meth:`CollisionChecker.gradients`).
Between polyhedra (convex hulls of meshes) d is not differentiable where the closest features switch
(a flat face parallel to another: any tilt brings a corner closer, at a rate the one witness pair does
not see), so the linearised step can end up to a few 1e-4 m below d_min there; keep a margin in d_min.
``min_distance`` ≥ 0 [m] (a negative one would allow penetration: refused). ``gain`` ∈ (0, 1] (1: the
formula above; smaller approaches the boundary more slowly, a velocity damper).
:class:`kinengine.DifferentialIK` takes it in ``constraints=[...]``.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import numpy.typing as npt

from ..errors import OptionError
from ..kinematics.options import checked_nonnegative
from .checker import CollisionChecker

FloatArray = npt.NDArray[np.float64]


class CollidingRobot(Protocol):
    """What CollisionAvoidance reads of the Robot passed in (a public method of :class:`kinengine.Robot`)."""

    def collision_checker(self) -> CollisionChecker: ...


class CollisionAvoidance:
    """G q̇ ≤ h keeping every checked pair at least ``min_distance`` [m] apart (module doc); pairs farther than
    ``influence_distance`` [m] are left out."""

    def __init__(
        self, min_distance: float = 0.01, influence_distance: float = 0.05, *, gain: float = 1.0
    ) -> None:
        min_distance = checked_nonnegative(min_distance, "min_distance [m]")
        influence_distance = checked_nonnegative(influence_distance, "influence_distance [m]")
        gain = checked_nonnegative(gain, "gain")
        if not influence_distance > min_distance:
            raise OptionError(
                f"influence_distance ({influence_distance!r}) must exceed min_distance ({min_distance!r}) [m]"
            )
        if not 0.0 < gain <= 1.0:
            raise OptionError(f"gain must be in (0, 1], got {gain!r}")
        self.min_distance, self.influence_distance, self.gain = (
            float(min_distance),
            float(influence_distance),
            gain,
        )
        self.last_distances: FloatArray = np.zeros(0)
        """The signed distances [m] of the pairs constrained by the last :meth:`inequalities` call."""

    def inequalities(self, robot: CollidingRobot, q: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]:
        """(G (m, dof), h (m,)) with G q̇ ≤ h [m/s] at q for a step of ``dt`` [s]: one row per pair within the
        influence distance (m = 0 rows when none is): a ``VelocityConstraint`` of
        :class:`kinengine.DifferentialIK`."""
        _, d, grad = robot.collision_checker().gradients(q, self.influence_distance)
        self.last_distances = d
        return -grad, self.gain * (d - self.min_distance) / dt


__all__ = ["CollidingRobot", "CollisionAvoidance"]
