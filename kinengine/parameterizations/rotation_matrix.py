"""Rotation matrix entries χ_R = (C11, C12, ..., C33) = C_IE.flatten() (row-major, 9 coordinates).

Ċ = [ω]x C with ω in I; column j of C, u = C[:, j], moves as u̇ = ω × u = −[u]x ω, so row 3i + j of
the 9x3 map E(χ) is row i of −[C[:, j]]x. E^T E = 2 I_3 for orthonormal C, hence E_inverse = ½ E^T,
the Moore–Penrose pseudo-inverse (ω = vee(skew(Ċ C^T)) for a consistent Ċ). E is linear in C, so
Ė = E(Ċ) with Ċ = [ω]x C. Never singular.
"""

from __future__ import annotations

import math

from .base import Component, Entries, Namespace, RotationParameterization, Values


def _rate_map(*C: Component) -> Entries:
    """Row-major entries of the 9x3 E with vec(Ċ) = E·ω (row 3i + j is row i of −[C[:, j]]x)."""
    c00, c01, c02, c10, c11, c12, c20, c21, c22 = C
    return (
        0.0, c20, -c10,  0.0, c21, -c11,  0.0, c22, -c12,
        -c20, 0.0, c00,  -c21, 0.0, c01,  -c22, 0.0, c02,
        c10, -c00, 0.0,  c11, -c01, 0.0,  c12, -c02, 0.0,
    )  # fmt: skip


class RotationMatrix(RotationParameterization):
    """χ_R = C_IE.flatten() (row-major); Ċ = [ω]x C, E: 9x3, E_inverse = ½ E^T. Never singular."""

    name = "rotation_matrix"
    labels = ("C11", "C12", "C13", "C21", "C22", "C23", "C31", "C32", "C33")
    singular_set = "none (E is defined everywhere)"
    alternatives: tuple[str, ...] = ()

    def _from_rotation(self, xp: Namespace, warn: bool, *C: Component) -> Entries:
        return C

    def _to_rotation(self, xp: Namespace, *chi: Component) -> Entries:
        return chi

    def _E(self, xp: Namespace, *chi: Component) -> Entries:
        return _rate_map(*chi)

    def _E_inverse(self, xp: Namespace, *chi: Component) -> Entries:
        E = _rate_map(*chi)  # ½ E^T: the 3x9 transpose of the 9x3 map, halved
        return tuple(0.5 * E[3 * row + column] for column in range(3) for row in range(9))

    def _E_dot(self, xp: Namespace, chi: Values, u: Values) -> Entries:
        a, b, c = u
        E = _rate_map(*chi)  # Ė = E(Ċ) with vec(Ċ) = E·ω
        return _rate_map(*(E[k] * a + E[k + 1] * b + E[k + 2] * c for k in range(0, 27, 3)))

    def _distance(self, xp: Namespace, *chi: Component) -> Component:
        return math.inf
