"""Unit quaternion χ_R = q = (w, x, y, z), Hamilton convention, scalar FIRST, canonical w >= 0.

C_IE = I + 2w[v]x + 2[v]x² with v = (x, y, z). (scipy's ``as_quat()`` is scalar LAST: (x, y, z, w).)
For ω in the inertial frame, Ċ = [ω]x C gives q̇ = ½ (0, ω) ⊗ q, i.e.

    E(q) = ½ H(q),  H(q) = [−v^T; w I − [v]x]   (4x3, H^T H = I_3 for |q| = 1).

(With ω in the body frame it would be q ⊗ (0, ω)/2, i.e. w I + [v]x.) E_inverse = 2 H(q)^T is the
Moore–Penrose pseudo-inverse of E: E_inverse·E = I_3 and E_inverse·q = 0 (it discards the radial part
of q̇ that a unit quaternion cannot have). Ė = ½ H(q̇) with q̇ = E(q)·ω. Never singular; the sign choice
w >= 0 is a branch cut at w = 0 (θ = π), where q jumps to −q.
"""

from __future__ import annotations

import math

from ._so3 import quaternion_from_matrix, rotation_entries
from .base import Component, Entries, Namespace, RotationParameterization, Values


def _half_H(w: Component, x: Component, y: Component, z: Component) -> Entries:
    """Row-major entries of ½ [−v^T; w I − [v]x] for q = (w, v)."""
    w, x, y, z = 0.5 * w, 0.5 * x, 0.5 * y, 0.5 * z
    return (-x, -y, -z, w, z, -y, -z, w, x, y, -x, w)


class Quaternion(RotationParameterization):
    """χ_R = (w, x, y, z), unit, scalar first, w >= 0; q̇ = ½ [−v^T; w I − [v]x]·ω (ω in I)."""

    name = "quaternion"
    labels = ("qw", "qx", "qy", "qz")
    singular_set = "none (E is defined everywhere; branch cut of the sign choice at w = 0)"
    alternatives: tuple[str, ...] = ()

    def _from_rotation(self, xp: Namespace, warn: bool, *C: Component) -> Entries:
        return quaternion_from_matrix(xp, *C)

    def _to_rotation(self, xp: Namespace, w: Component, x: Component, y: Component, z: Component) -> Entries:
        s = 2.0 / (w * w + x * x + y * y + z * z)  # C(q/|q|) = I + s w [v]x + s [v]x², any nonzero q
        return rotation_entries(s * w, s, x, y, z)

    def _E(self, xp: Namespace, w: Component, x: Component, y: Component, z: Component) -> Entries:
        return _half_H(w, x, y, z)

    def _E_inverse(self, xp: Namespace, w: Component, x: Component, y: Component, z: Component) -> Entries:
        w, x, y, z = 2.0 * w, 2.0 * x, 2.0 * y, 2.0 * z
        return (-x, w, -z, y, -y, z, w, -x, -z, -y, x, w)

    def _E_dot(self, xp: Namespace, chi: Values, u: Values) -> Entries:
        a, b, c = u
        E = _half_H(*chi)
        return _half_H(*(E[k] * a + E[k + 1] * b + E[k + 2] * c for k in range(0, 12, 3)))  # ½ H(q̇), q̇ = E·ω

    def _distance(self, xp: Namespace, w: Component, x: Component, y: Component, z: Component) -> Component:
        return math.inf
