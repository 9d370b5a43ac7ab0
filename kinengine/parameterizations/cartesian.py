"""Cartesian coordinates χ_P = p = (x, y, z) [m] of the frame origin in the inertial frame: E_P = I."""

from __future__ import annotations

import math

from .base import PositionParameterization


class Cartesian(PositionParameterization):
    """χ_P = (x, y, z) [m]; χ̇_P = v, so E = E_inverse = I_3 and Ė = 0. Never singular."""

    name = "cartesian"
    labels = ("x", "y", "z")
    singular_set = "none (E = I everywhere)"
    alternatives = ()

    def _from_position(self, xp, x, y, z):
        return x, y, z

    def _to_position(self, xp, x, y, z):
        return x, y, z

    def _E(self, xp, x, y, z):
        return (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)

    _E_inverse = _E

    def _E_dot(self, xp, chi, u):
        return (0.0,) * 9

    def _distance(self, xp, x, y, z):
        return math.inf
