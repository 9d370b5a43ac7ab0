"""Cartesian coordinates χ_P = p = (x, y, z) [m] of the frame origin in the inertial frame: E_P = I."""

from __future__ import annotations

import math

from .base import Component, Entries, Namespace, PositionParameterization, Values


class Cartesian(PositionParameterization):
    """χ_P = (x, y, z) [m]; χ̇_P = v, so E = E_inverse = I_3 and Ė = 0. Never singular."""

    name = "cartesian"
    labels = ("x", "y", "z")
    singular_set = "none (E = I everywhere)"
    alternatives: tuple[str, ...] = ()

    def _from_position(self, xp: Namespace, x: Component, y: Component, z: Component) -> Entries:
        return x, y, z

    _to_position = _from_position

    def _E(self, xp: Namespace, x: Component, y: Component, z: Component) -> Entries:
        return (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)

    _E_inverse = _E

    def _E_dot(self, xp: Namespace, chi: Values, u: Values) -> Entries:
        return (0.0,) * 9

    def _distance(self, xp: Namespace, x: Component, y: Component, z: Component) -> Component:
        return math.inf
